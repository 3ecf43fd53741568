// SPDX-License-Identifier: MIT
// What a circular test's diagnostic asks of the machine, in the machine's terms: "raise X's backlash
// compensation by 3.0 µm", not only "backlash_x_um 3.0". Shared by the report, `circle analyze` and
// the page (through the report's JSON).
#pragma once

#include <string>

namespace ballbar::report {

/// The action for one diagnostic of a test in `plane` ("XY", "YZ", "ZX"): its key (ballbar-trace/1,
/// e.g. "backlash_x_um", "squareness_um_per_m") and value ± standard uncertainty in the key's unit.
/// Empty for a value within twice its uncertainty of zero (nothing to correct that the data shows), for
/// keys that ask for nothing by themselves (a cyclic error's pitch, a vibration's frequency) and for
/// unknown keys.
std::string diagnostic_action(const std::string& key, double value, double std_uncertainty, const std::string& plane);

}  // namespace ballbar::report
