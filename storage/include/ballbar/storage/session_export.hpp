// SPDX-License-Identifier: MIT
// A session as JSON (`ballbar-session/1`) and as CSV (points.csv + samples.csv). Layouts: docs/storage.md.
#pragma once

#include <cstdint>
#include <filesystem>
#include <ostream>
#include <string>

#include "ballbar/storage/store.hpp"

namespace ballbar::storage {

/// The session's metadata (with machine, instrument and extra metadata as JSON objects), transitions,
/// results (payload as JSON), models those results came from, sample count, and — when `with_points` —
/// every point. One JSON document, indented by `indent` (-1: compact).
std::string session_json(Store& store, std::int64_t session_id, bool with_points = true, int indent = 2);

/// One line per session (id, uuid, state, source, machine, started/ended, counts) as a JSON array.
std::string sessions_json(Store& store, int indent = 2);

/// points CSV: index,location,point,step,X_mm,Y_mm,Z_mm,A_deg,B_deg,C_deg,socket_x_mm,socket_y_mm,
/// socket_z_mm,nominal_mm,measured_mm,std_mm,n,first_seq,last_seq,time_s,bar_temp_C,air_temp_C,
/// machine_temp_C (empty field = not given).
void write_points_csv(Store& store, std::int64_t session_id, std::ostream& out);
/// samples CSV: seq,device_time_us,displacement_nm,flags,bar_temp_C — streamed, any length.
void write_samples_csv(Store& store, std::int64_t session_id, std::ostream& out);
/// Creates `dir` if needed and writes dir/points.csv and dir/samples.csv. Throws std::runtime_error.
void export_csv(Store& store, std::int64_t session_id, const std::filesystem::path& dir);
/// Writes the points' and the samples' CSV to the two files given (both or neither replaced).
void export_csv_files(Store& store, std::int64_t session_id, const std::filesystem::path& points,
                      const std::filesystem::path& samples);

}  // namespace ballbar::storage
