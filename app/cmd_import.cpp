// SPDX-License-Identifier: MIT
// `ballbar import FILE`: a `ballbar-readings/1` file into a new session (source `imported`), in one
// transaction. An invalid file is refused whole (exit 2) with its line number and the problem.
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

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
};

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
    std::optional<storage::ReadingsStream> stream;
    try {
        stream.emplace(storage::ReadingsStream::open(o.file));
    } catch (const storage::ReadingsFileError& e) {
        throw CliError(kExitUsage, o.file + ": " + e.what() + " (nothing imported)");
    }
    storage::ImportedReadings r;
    try {
        storage::Store store(resolve_db_path(globals));
        try {
            r = storage::import_readings_stream(store, *stream, o.file);
        } catch (const storage::ReadingsFileError& e) {
            throw CliError(kExitUsage, o.file + ": " + e.what() + " (nothing imported)");
        }
        for (const auto& w : r.warnings) std::cerr << "ballbar: warning: " << o.file << ": " << w << '\n';
        if (r.nominal_mismatches > 0)
            std::cerr << "ballbar: warning: " << o.file << ": " << mismatch_summary(r) << '\n';
        const auto info = store.session(r.session);
        if (o.json) {
            nlohmann::json j = {{"session", r.session},
                                {"uuid", info.uuid},
                                {"readings", r.readings},
                                {"warnings", r.warnings},
                                {"nominal_mismatches", r.nominal_mismatches}};
            std::cout << j.dump(2) << '\n';
        } else {
            std::cout << "imported " << r.readings << " readings from " << o.file << " into session " << r.session
                      << " (" << info.uuid << ")\n";
        }
        return kExitOk;
    } catch (const storage::StorageError& e) {
        throw CliError(kExitFailure, std::string(e.what()) + " (nothing imported)");
    }
}

/// A ballbar-trace/1 file: a circular session (procedure "circular") with every sample.
int run_import_trace(const ImportOptions& o, const Globals& globals) {
    storage::TraceFile trace;
    try {
        trace = storage::read_trace_file(o.file);
    } catch (const storage::TraceFileError& e) {
        throw CliError(kExitUsage, o.file + ": " + e.what() + " (nothing imported)");
    }
    for (const auto& w : trace.warnings) std::cerr << "ballbar: warning: " << o.file << ": " << w << '\n';
    try {
        storage::Store store(resolve_db_path(globals));
        const auto id = storage::import_trace(store, trace, o.file);
        const auto info = store.session(id);
        if (o.json) {
            nlohmann::json j = {{"session", id},
                                {"uuid", info.uuid},
                                {"samples", trace.samples.size()},
                                {"format", "ballbar-trace/1"},
                                {"warnings", trace.warnings}};
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
    sub->add_option("FILE", opts->file, "readings file (docs/formats/readings.md) or trace file")->required();
    sub->add_flag("--json", opts->json, "print the new session as JSON");
    sub->callback(
        [opts, &globals] { globals.action = [opts, &globals] { return ballbar::app::run_import(*opts, globals); }; });
}
