// SPDX-License-Identifier: MIT
// JSON forms of the machine geometry and the instrument, as in the `machine` and `instrument` headers of
// `ballbar-readings/1` (docs/formats/readings.md). Lengths in mm.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/analysis/types.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::storage {

/// A JSON value that does not describe a machine or instrument; the message names the key and problem.
class FormatError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// {"type":…, "name":…, <the type's geometry keys>} — only the keys the type uses; full double precision.
std::string machine_to_json(const analysis::MachineGeometry& machine);
/// Parses a `machine` object. The type's geometry keys are required (each an array of 3 finite numbers);
/// keys the type does not use, and unknown keys, are ignored with a note appended to `warnings`.
analysis::MachineGeometry machine_from_json(std::string_view json, std::vector<std::string>* warnings = nullptr);

std::string instrument_to_json(const Instrument& instrument);
/// Known keys: model, serial, firmware (strings), calibrated_length_mm (number > 0), calibration_date
/// (string); other keys are kept in Instrument::extra_json.
Instrument instrument_from_json(std::string_view json);

}  // namespace ballbar::storage
