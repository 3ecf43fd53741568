// SPDX-License-Identifier: MIT
// `ballbar import FILE`: a `ballbar-readings/1` file into a new session (source `imported`), in one
// transaction. An invalid file is refused whole (exit 2) with its line number and the problem. The
// SHA-256 of the file's bytes is stored with the session (storage/imports.hpp): content imported before
// is refused (exit 2) naming the session it duplicates, unless --allow-duplicate.
#include <iostream>
#include <nlohmann/json.hpp>

#include "ballbar/storage/imports.hpp"
#include "ballbar/storage/readings.hpp"
#include "ballbar/storage/readings_file.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/storage/trace_file.hpp"
#include "command.hpp"

namespace ballbar::app {
namespace {

struct ImportOptions {
    std::string file;
    bool json = false;
    bool allow_duplicate = false;
};

/// The file's bytes and their SHA-256, read once.
struct Content {
    std::string bytes;
    std::string sha256;
};

/// Refuses content imported before (exit 2, naming the session), or with --allow-duplicate warns and
/// returns the sessions it duplicates. Runs in the import's transaction, so two imports of one file at
/// once cannot both pass.
std::vector<std::int64_t> check_duplicate(storage::Store& store, const Content& c, const ImportOptions& o) {
    const auto before = storage::imports_of_content(store, c.sha256);
    std::vector<std::int64_t> ids;
    for (const auto& r : before) ids.push_back(r.session_id);
    if (before.empty()) return ids;
    const auto& first = before.front();
    std::string what = "session " + std::to_string(first.session_id) + " (imported from " + first.file_name + " at " +
                       first.imported_at + ")";
    if (before.size() > 1) what += " and " + std::to_string(before.size() - 1) + " more";
    if (!o.allow_duplicate)
        throw CliError(kExitUsage, o.file + ": the same content (SHA-256 " + c.sha256.substr(0, 12) +
                                       "…) was already imported as " + what +
                                       "; nothing imported (--allow-duplicate imports it again)");
    std::cerr << "ballbar: warning: " << o.file << ": the same content as " << what
              << ", imported again (--allow-duplicate)\n";
    return ids;
}

nlohmann::json ids_json(const std::vector<std::int64_t>& ids) {
    nlohmann::json j = nlohmann::json::array();
    for (auto id : ids) j.push_back(id);
    return j;
}

std::string mismatch_summary(const storage::ReadingsFile& f) {
    const auto& m = f.nominal_mismatches;
    std::string lines;
    double worst = 0;
    for (std::size_t i = 0; i < m.size(); ++i) {
        if (i < 10) lines += (i ? ", " : "") + std::to_string(m[i].line);
        worst = std::max(worst, std::abs(m[i].file_nominal_mm - m[i].computed_nominal_mm));
    }
    if (m.size() > 10) lines += ", …";
    return std::to_string(m.size()) +
           " row(s) give a nominal_mm that differs from the length recomputed from the "
           "machine geometry by more than 0.001 mm (largest " +
           std::to_string(worst) + " mm; lines " + lines +
           "): the producer's geometry or conventions may disagree with this file's machine header";
}

int run_import_trace(const ImportOptions& o, const Content& c, const Globals& globals);

int run_import(const ImportOptions& o, const Globals& globals) {
    Content c;
    c.bytes = read_file(o.file, "file");
    c.sha256 = storage::sha256_hex(c.bytes);
    if (storage::looks_like_trace(c.bytes.substr(0, 64))) return run_import_trace(o, c, globals);
    storage::ReadingsFile file;
    try {
        file = storage::read_readings_file(o.file);
    } catch (const storage::ReadingsFileError& e) {
        throw CliError(kExitUsage, o.file + ": " + e.what() + " (nothing imported)");
    }
    for (const auto& w : file.warnings) std::cerr << "ballbar: warning: " << o.file << ": " << w << '\n';
    if (!file.nominal_mismatches.empty()) {
        std::cerr << "ballbar: warning: " << o.file << ": " << mismatch_summary(file) << '\n';
    }
    try {
        storage::Store store(resolve_db_path(globals));
        storage::Transaction tx(store.db());
        const auto duplicates = check_duplicate(store, c, o);
        const auto id = storage::import_readings(store, file, o.file);
        storage::record_import(store, id, c.sha256, o.file, static_cast<std::int64_t>(c.bytes.size()));
        tx.commit();
        const auto info = store.session(id);
        if (o.json) {
            nlohmann::json j = {{"session", id},
                                {"uuid", info.uuid},
                                {"readings", file.set.readings.size()},
                                {"warnings", file.warnings},
                                {"nominal_mismatches", file.nominal_mismatches.size()},
                                {"sha256", c.sha256},
                                {"duplicate_of", ids_json(duplicates)}};
            std::cout << j.dump(2) << '\n';
        } else {
            std::cout << "imported " << file.set.readings.size() << " readings from " << o.file << " into session "
                      << id << " (" << info.uuid << ")\n";
        }
        return kExitOk;
    } catch (const storage::StorageError& e) {
        throw CliError(kExitFailure, std::string(e.what()) + " (nothing imported)");
    }
}

/// A ballbar-trace/1 file: a circular session (procedure "circular") with every sample.
int run_import_trace(const ImportOptions& o, const Content& c, const Globals& globals) {
    storage::TraceFile trace;
    try {
        trace = storage::read_trace_file(o.file);
    } catch (const storage::TraceFileError& e) {
        throw CliError(kExitUsage, o.file + ": " + e.what() + " (nothing imported)");
    }
    for (const auto& w : trace.warnings) std::cerr << "ballbar: warning: " << o.file << ": " << w << '\n';
    try {
        storage::Store store(resolve_db_path(globals));
        storage::Transaction tx(store.db());
        const auto duplicates = check_duplicate(store, c, o);
        const auto id = storage::import_trace(store, trace, o.file);
        storage::record_import(store, id, c.sha256, o.file, static_cast<std::int64_t>(c.bytes.size()));
        tx.commit();
        const auto info = store.session(id);
        if (o.json) {
            nlohmann::json j = {{"session", id},
                                {"uuid", info.uuid},
                                {"samples", trace.samples.size()},
                                {"format", "ballbar-trace/1"},
                                {"warnings", trace.warnings},
                                {"sha256", c.sha256},
                                {"duplicate_of", ids_json(duplicates)}};
            std::cout << j.dump(2) << '\n';
        } else {
            std::cout << "imported " << trace.samples.size() << " samples of a circular test from " << o.file
                      << " into session " << id << " (" << info.uuid << ")\n";
        }
        return kExitOk;
    } catch (const storage::StorageError& e) {
        throw CliError(kExitFailure, std::string(e.what()) + " (nothing imported)");
    }
}

}  // namespace
}  // namespace ballbar::app

BALLBAR_COMMAND(import) {
    auto opts = std::make_shared<ballbar::app::ImportOptions>();
    auto* sub = root.add_subcommand("import", "Import a ballbar-readings/1 or ballbar-trace/1 file into a new session");
    sub->add_option("FILE", opts->file, "readings or trace file (docs/formats/readings.md, docs/formats/trace.md)")
        ->required();
    sub->add_flag("--json", opts->json, "print the new session as JSON");
    sub->add_flag("--allow-duplicate", opts->allow_duplicate,
                  "import content that was imported before (refused by default, naming the session)");
    sub->callback(
        [opts, &globals] { globals.action = [opts, &globals] { return ballbar::app::run_import(*opts, globals); }; });
}
