// SPDX-License-Identifier: MIT
// Sessions as ReadingSets: what identification, discovery and reports read, and what `import` writes.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/analysis/reading.hpp"
#include "ballbar/storage/readings_file.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::storage {

/// The session's points as readings (in point order), with the session's machine geometry.
analysis::ReadingSet load_readings(Store& store, std::int64_t session_id);

/// The session's metadata as a readings-file header (instrument, operator, started_at, notes, and the
/// unknown keys an imported file carried).
ReadingsMetadata readings_metadata(const SessionInfo& session);

/// Stores a parsed readings file as a new session (source `imported`, state `completed`), all in one
/// transaction: on any error nothing is stored. `origin` (e.g. the file name) goes into the audit trail.
std::int64_t import_readings(Store& store, const ReadingsFile& file, std::string_view origin = {});

/// What a streamed import stored and found.
struct ImportedReadings {
    std::int64_t session = 0;
    std::size_t readings = 0;
    std::vector<std::string> warnings;
    std::size_t nominal_mismatches = 0;     ///< rows whose nominal_mm disagrees with the geometry
    std::vector<int> first_mismatch_lines;  ///< the first ten of them
    double worst_mismatch_mm = 0;           ///< the largest disagreement
};

/// Streams a readings file into a new session as import_readings() does — one transaction, nothing
/// stored on any error — but in batches of `batch` points, in memory independent of the file's length.
/// Throws ReadingsFileError (the file) or StorageError (the database).
ImportedReadings import_readings_stream(Store& store, ReadingsStream& stream, std::string_view origin = {},
                                        std::size_t batch = 4096);

}  // namespace ballbar::storage
