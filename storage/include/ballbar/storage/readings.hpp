// SPDX-License-Identifier: MIT
// Sessions as ReadingSets: what identification, discovery and reports read, and what `import` writes.
#pragma once

#include <cstdint>
#include <string_view>

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

}  // namespace ballbar::storage
