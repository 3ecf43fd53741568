// SPDX-License-Identifier: MIT
// The compensation proof on the emulator (issue 6): an emulated TTTRR machine with seed-like errors
// (rotary-block location errors dominant, as Lei & Hsu found), the identification plan measured on
// it with 0.1 µm-class bar noise, the identified model, a test path compensated through the model's
// inverse Jacobian, written as an NC program, run on the emulated machine, and the tool-ball error
// relative to the table before and after, per axis. `ballbar demo --compensate` calls
// run_compensation_demo.
#pragma once

#include <cstdint>
#include <ostream>

namespace ballbar::app {

struct CompensationDemoOptions {
    std::uint64_t seed = 1;    ///< socket set-up offsets and bar noise
    double noise_um = 0.1;     ///< standard deviation of a bar reading
    int path_points = 360;     ///< test path blocks
    bool first_order = false;  ///< compensate with the first-order solution instead of the exact one
};

/// What a session's report shows of the demo: the test path's RMS error per axis (X, Y, Z), µm.
struct CompensationDemoResult {
    double before_um[3]{};
    double after_um[3]{};
    int path_blocks = 0;
    bool exact = true;  ///< the exact (Newton) solution; false: first order
};

/// Runs the demo and prints a report (text, or the JSON object of docs/compensation.md); with
/// `result`, also fills it. Returns an exit code (0 ok, 1 when identification failed to converge).
int run_compensation_demo(const CompensationDemoOptions& options, std::ostream& out, bool json,
                          CompensationDemoResult* result = nullptr);

}  // namespace ballbar::app
