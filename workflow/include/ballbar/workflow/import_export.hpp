// SPDX-License-Identifier: MIT
// Sessions in and out of the database as use cases (`ballbar import` and `ballbar export`, and any
// front end): a `ballbar-readings/1` or `ballbar-trace/1` file into a new session with its content's
// SHA-256 (a duplicate refused unless allowed), and a stored session as a readings file, a trace file or
// its whole JSON (docs/storage.md).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ballbar/storage/store.hpp"

namespace ballbar::workflow {

struct ImportOptions {
    bool allow_duplicate = false;  ///< import content that was imported before (it is still said)
};

struct ImportResult {
    std::int64_t session = 0;
    std::string uuid;
    bool trace = false;                      ///< a ballbar-trace/1 file (a circular test); else readings
    std::size_t readings = 0;                ///< of a readings file
    std::size_t samples = 0;                 ///< of a trace file
    std::size_t nominal_mismatches = 0;      ///< readings whose nominal_mm disagrees with the geometry
    std::string sha256;                      ///< of the file's bytes
    std::vector<std::int64_t> duplicate_of;  ///< sessions imported before from the same content
    /// What the operator should read: the file's own warnings, a geometry that disagrees with the
    /// nominal lengths, and a duplicate imported again.
    std::vector<std::string> warnings;
    std::vector<std::string> file_warnings;  ///< the file's own warnings alone (a subset of `warnings`)
};

/// Imports `file` into a new session of the database at `db_path` (created if absent), in one
/// transaction: a file refused anywhere stores nothing. Error (bad input) for a file that is neither
/// format, an invalid line (its number and the problem), content imported before (naming the session,
/// unless allow_duplicate); (failed) for the database.
ImportResult import_file(const std::string& file, const std::string& db_path, const ImportOptions& options = {});

enum class ExportFormat {
    readings,  ///< the interchange file of its points (docs/formats/readings.md)
    trace,     ///< a circular test's samples (docs/formats/trace.md)
    json,      ///< the whole session: metadata, transitions, points, results
};

/// The session as text in `format`. Error (failed) for a session without points (readings) or that is
/// not a circular test (trace).
std::string export_session(storage::Store& store, std::int64_t session, ExportFormat format);

}  // namespace ballbar::workflow
