// SPDX-License-Identifier: MIT
// The work-offset and tool table `ballbar-nc-offsets/1` (docs/compensation.md, "The offsets table"):
// what `compensate --offsets` reads, one reader and one writer.
#pragma once

#include <string>
#include <string_view>

#include "ballbar/analysis/nc_interpreter.hpp"

namespace ballbar::storage {

inline constexpr std::string_view kOffsetsFormat = "ballbar-nc-offsets/1";

/// Strict: unknown keys, work offsets other than G54–G59 and G59.1–G59.3, tool keys that are not tool
/// numbers, values that are not numbers or lie outside ±100 m (±36000° for rotary offsets) are refused
/// with FormatError (storage/machine_json.hpp) naming the key.
analysis::NcOffsetTable offsets_from_json(std::string_view json);
/// Every key written, "format" first; rotary offsets in degrees.
std::string offsets_to_json(const analysis::NcOffsetTable& table);

}  // namespace ballbar::storage
