// SPDX-License-Identifier: MIT
#include "ballbar/workflow/import_export.hpp"

#include <optional>
#include <string>

#include "ballbar/fileio/input.hpp"
#include "ballbar/storage/imports.hpp"
#include "ballbar/storage/readings.hpp"
#include "ballbar/storage/readings_file.hpp"
#include "ballbar/storage/session_export.hpp"
#include "ballbar/storage/trace_file.hpp"
#include "ballbar/workflow/error.hpp"

namespace ballbar::workflow {
namespace {

/// The SHA-256 and size of what was read of the file: the bytes the parser read, hashed as it read
/// them (one read of the file: what is hashed is what was imported).
struct Content {
    std::string sha256;
    std::int64_t bytes = 0;
};

/// Refuses content imported before (naming the session), or with allow_duplicate says so in the
/// result's warnings and lists the sessions it duplicates. Runs in the import's transaction, so two
/// imports of one file at once cannot both pass.
void check_duplicate(storage::Store& store, const Content& c, const std::string& file, const ImportOptions& o,
                     ImportResult& result) {
    const auto before = storage::imports_of_content(store, c.sha256);
    for (const auto& r : before) result.duplicate_of.push_back(r.session_id);
    if (before.empty()) return;
    const auto& first = before.front();
    std::string what = "session " + std::to_string(first.session_id) + " (imported from " + first.file_name + " at " +
                       first.imported_at + ")";
    if (before.size() > 1) what += " and " + std::to_string(before.size() - 1) + " more";
    if (!o.allow_duplicate)
        throw Error(ErrorCategory::bad_input, file + ": the same content (SHA-256 " + c.sha256.substr(0, 12) +
                                                  "…) was already imported as " + what +
                                                  "; nothing imported (--allow-duplicate imports it again)");
    result.warnings.push_back("the same content as " + what + ", imported again (--allow-duplicate)");
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

Error nothing_imported(const std::string& file, const std::exception& e) {
    return Error(ErrorCategory::bad_input, file + ": " + e.what() + " (nothing imported)");
}

/// A ballbar-trace/1 file: a circular session (procedure "circular") with every sample.
ImportResult import_trace(const std::string& file, const std::string& db_path, const ImportOptions& o) {
    storage::TraceFile trace;
    Content c;
    try {
        // Read once (at most the trace reader's cap): parsed and hashed from the same bytes.
        const std::string text = fileio::read_text(file, "trace file");
        trace = storage::parse_trace(text);
        c.sha256 = storage::sha256_hex(text);
        c.bytes = static_cast<std::int64_t>(text.size());
    } catch (const fileio::FileError& e) {
        throw nothing_imported(file, e);
    } catch (const storage::TraceFileError& e) {
        throw nothing_imported(file, e);
    }
    ImportResult result;
    result.trace = true;
    result.file_warnings = trace.warnings;
    result.warnings = trace.warnings;
    result.samples = trace.samples.size();
    result.sha256 = c.sha256;
    try {
        storage::Store store(db_path);
        storage::Transaction tx(store.db());
        check_duplicate(store, c, file, o, result);
        result.session = storage::import_trace(store, trace, file);
        storage::record_import(store, result.session, c.sha256, file, c.bytes);
        tx.commit();
        result.uuid = store.session(result.session).uuid;
        return result;
    } catch (const storage::StorageError& e) {
        throw Error(ErrorCategory::failed, std::string(e.what()) + " (nothing imported)");
    }
}

}  // namespace

ImportResult import_file(const std::string& file, const std::string& db_path, const ImportOptions& o) {
    try {
        if (storage::looks_like_trace(fileio::read_head(file, "file to import", 64)))
            return import_trace(file, db_path, o);
    } catch (const fileio::FileError& e) {
        throw Error(category_of(e), e.what());
    }
    // Streamed into the database in batches, in one transaction (memory independent of the file's
    // length); an invalid line anywhere stores nothing.
    storage::Sha256 hash;
    Content c;
    std::optional<storage::ReadingsStream> stream;
    try {
        stream.emplace(storage::ReadingsStream::open(file, [&hash, &c](std::string_view bytes) {
            hash.update(bytes);
            c.bytes += static_cast<std::int64_t>(bytes.size());
        }));
    } catch (const storage::ReadingsFileError& e) {
        throw nothing_imported(file, e);
    }
    ImportResult result;
    try {
        storage::Store store(db_path);
        storage::Transaction tx(store.db());
        storage::ImportedReadings r;
        try {
            r = storage::import_readings_stream(store, *stream, file);
        } catch (const storage::ReadingsFileError& e) {
            throw nothing_imported(file, e);
        }
        // The whole file has been read (and hashed) now that it proved a readings file; a duplicate rolls
        // the import back.
        c.sha256 = hash.hex();
        result.sha256 = c.sha256;
        check_duplicate(store, c, file, o, result);
        storage::record_import(store, r.session, c.sha256, file, c.bytes);
        tx.commit();
        result.session = r.session;
        result.uuid = store.session(r.session).uuid;
        result.readings = r.readings;
        result.nominal_mismatches = r.nominal_mismatches;
        result.file_warnings = r.warnings;
        std::vector<std::string> warnings = r.warnings;
        if (r.nominal_mismatches > 0) warnings.push_back(mismatch_summary(r));
        warnings.insert(warnings.end(), result.warnings.begin(), result.warnings.end());  // the duplicate's
        result.warnings = std::move(warnings);
        return result;
    } catch (const storage::StorageError& e) {
        throw Error(ErrorCategory::failed, std::string(e.what()) + " (nothing imported)");
    }
}

std::string export_session(storage::Store& store, std::int64_t session, ExportFormat format) {
    switch (format) {
        case ExportFormat::readings: {
            const auto set = storage::load_readings(store, session);
            if (set.readings.empty())
                throw Error(ErrorCategory::failed, "session " + std::to_string(session) + " has no points");
            return storage::format_readings(set, storage::readings_metadata(store.session(session)));
        }
        case ExportFormat::trace:
            try {
                return storage::format_trace(storage::load_trace(store, session));
            } catch (const storage::StorageError&) {
                throw;
            } catch (const std::runtime_error& e) {  // not a circular test
                throw Error(ErrorCategory::failed, e.what());
            }
        case ExportFormat::json:
            return storage::session_json(store, session) + "\n";
    }
    throw Error(ErrorCategory::internal, "unknown export format");
}

}  // namespace ballbar::workflow
