// SPDX-License-Identifier: MIT
// `ballbar import FILE`: a `ballbar-readings/1` file into a new session (source `imported`), in one
// transaction. An invalid file is refused whole (exit 2) with its line number and the problem. The
// SHA-256 of the file's bytes is stored with the session (storage/imports.hpp): content imported before
// is refused (exit 2) naming the session it duplicates, unless --allow-duplicate.
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "ballbar/fileio/input.hpp"
#include "ballbar/storage/imports.hpp"
#include "ballbar/storage/readings.hpp"
#include "ballbar/storage/readings_file.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/storage/trace_file.hpp"
#include "command.hpp"
#include "files.hpp"

namespace ballbar::app {
namespace {

struct ImportOptions {
    std::string file;
    bool json = false;
    bool allow_duplicate = false;
};

/// The SHA-256 and size of what was read of the file: the bytes the parser read, hashed as it read
/// them (one read of the file: what is hashed is what was imported).
struct Content {
    std::string sha256;
    std::int64_t bytes = 0;
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
        throw Error(ErrorCategory::bad_input, o.file + ": the same content (SHA-256 " + c.sha256.substr(0, 12) +
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

std::string mismatch_summary(const storage::ImportedReadings& r) {
    std::string lines;
    for (std::size_t i = 0; i < r.first_mismatch_lines.size(); ++i)
        lines += (i ? ", " : "") + std::to_string(r.first_mismatch_lines[i]);
    if (r.nominal_mismatches > r.first_mismatch_lines.size()) lines += ", …";
    return std::to_string(r.nominal_mismatches) +
           " row(s) give a nominal_mm that differs from the length recomputed from the "
           "machine geometry by more than 0.001 mm (largest " +
           std::to_string(r.worst_mismatch_mm) + " mm; lines " + lines +
           "): the producer's geometry or conventions may disagree with this file's machine header";
}

int run_import_trace(const ImportOptions& o, const Globals& globals);

/// Streams the file into the database in batches, in one transaction (memory independent of the
/// file's length); an invalid line anywhere stores nothing.
int run_import(const ImportOptions& o, const Globals& globals) {
    if (storage::looks_like_trace(fileio::read_head(o.file, "file to import", 64))) return run_import_trace(o, globals);
    storage::Sha256 hash;
    Content c;
    std::optional<storage::ReadingsStream> stream;
    try {
        stream.emplace(storage::ReadingsStream::open(o.file, [&hash, &c](std::string_view bytes) {
            hash.update(bytes);
            c.bytes += static_cast<std::int64_t>(bytes.size());
        }));
    } catch (const storage::ReadingsFileError& e) {
        throw Error(ErrorCategory::bad_input, o.file + ": " + e.what() + " (nothing imported)");
    }
    storage::ImportedReadings r;
    try {
        storage::Store store(resolve_db_path(globals));
        storage::Transaction tx(store.db());
        try {
            r = storage::import_readings_stream(store, *stream, o.file);
        } catch (const storage::ReadingsFileError& e) {
            throw Error(ErrorCategory::bad_input, o.file + ": " + e.what() + " (nothing imported)");
        }
        // The whole file has been read (and hashed) now that it proved a readings file; a duplicate rolls
        // the import back.
        c.sha256 = hash.hex();
        const auto duplicates = check_duplicate(store, c, o);
        storage::record_import(store, r.session, c.sha256, o.file, c.bytes);
        tx.commit();
        for (const auto& w : r.warnings) std::cerr << "ballbar: warning: " << o.file << ": " << w << '\n';
        if (r.nominal_mismatches > 0)
            std::cerr << "ballbar: warning: " << o.file << ": " << mismatch_summary(r) << '\n';
        const auto info = store.session(r.session);
        if (o.json) {
            nlohmann::json j = {{"session", r.session},
                                {"uuid", info.uuid},
                                {"readings", r.readings},
                                {"warnings", r.warnings},
                                {"nominal_mismatches", r.nominal_mismatches},
                                {"sha256", c.sha256},
                                {"duplicate_of", ids_json(duplicates)}};
            std::cout << j.dump(2) << '\n';
        } else {
            std::cout << "imported " << r.readings << " readings from " << o.file << " into session " << r.session
                      << " (" << info.uuid << ")\n";
        }
        return kExitOk;
    } catch (const storage::StorageError& e) {
        throw Error(ErrorCategory::failed, std::string(e.what()) + " (nothing imported)");
    }
}

/// A ballbar-trace/1 file: a circular session (procedure "circular") with every sample.
int run_import_trace(const ImportOptions& o, const Globals& globals) {
    storage::TraceFile trace;
    Content c;
    try {
        // Read once (at most the trace reader's cap): parsed and hashed from the same bytes.
        const std::string text = fileio::read_text(o.file, "trace file");
        trace = storage::parse_trace(text);
        c.sha256 = storage::sha256_hex(text);
        c.bytes = static_cast<std::int64_t>(text.size());
    } catch (const fileio::FileError& e) {
        throw Error(ErrorCategory::bad_input, o.file + ": " + e.what() + " (nothing imported)");
    } catch (const storage::TraceFileError& e) {
        throw Error(ErrorCategory::bad_input, o.file + ": " + e.what() + " (nothing imported)");
    }
    for (const auto& w : trace.warnings) std::cerr << "ballbar: warning: " << o.file << ": " << w << '\n';
    try {
        storage::Store store(resolve_db_path(globals));
        storage::Transaction tx(store.db());
        const auto duplicates = check_duplicate(store, c, o);
        const auto id = storage::import_trace(store, trace, o.file);
        storage::record_import(store, id, c.sha256, o.file, c.bytes);
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
        throw Error(ErrorCategory::failed, std::string(e.what()) + " (nothing imported)");
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
