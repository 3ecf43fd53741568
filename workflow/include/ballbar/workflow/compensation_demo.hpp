// SPDX-License-Identifier: MIT
// The compensation proof on the emulator (`ballbar demo --compensate`, and any front end): an emulated
// TTTRR machine with seed-like errors (rotary-block location errors dominant, as Lei & Hsu found), the
// identification plan measured on it with 0.1 µm-class bar noise, the identified model, a test path
// compensated through the model's inverse Jacobian, written as an NC program, run on the emulated
// machine, and the tool-ball error relative to the table before and after, per axis.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "ballbar/analysis/identify.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::workflow {

struct CompensationDemoOptions {
    std::uint64_t seed = 1;    ///< socket set-up offsets and bar noise
    double noise_um = 0.1;     ///< standard deviation of a bar reading
    int path_points = 360;     ///< test path blocks (at least 8)
    bool first_order = false;  ///< compensate with the first-order solution instead of the exact one
};

/// One identified parameter next to what the emulated machine really has.
struct IdentifiedParam {
    analysis::ParamEstimate estimate;
    double true_value = 0;
    /// What this plan can see of the truth: the same fit on noise-free readings (EZZ held at zero, so
    /// EXX − EZZ, EYY − EZZ and the locations the common scale moves). An estimate is judged against it.
    double identifiable_value = 0;
};

struct CompensationDemo {
    std::size_t locations = 0;                  ///< SSM locations of the plan
    std::size_t readings = 0;                   ///< bar readings measured
    std::vector<std::string> not_identifiable;  ///< what the plan says it cannot reach
    analysis::FitSummary fit;
    std::vector<IdentifiedParam> identified;  ///< the fit's estimates of a parameter, in its order
    int path_blocks = 0;
    std::size_t singular_blocks = 0;  ///< blocks whose rotary correction was held (near a singularity)
    bool exact = true;                ///< the exact (Newton) solution; false: first order
    double rms_before_um[3]{};        ///< RMS tool-ball error along the path, X, Y, Z
    double rms_after_um[3]{};
    double max_after_um = 0;
    /// before / after per axis (0 when after is 0)
    double improvement(int axis) const;
};

/// Runs the demo. Deterministic for a seed.
CompensationDemo run_compensation_demo(const CompensationDemoOptions& options);

/// Stores the demo's before/after as a `compensation` result of `session` (its report shows them).
void store_compensation_demo(storage::Store& store, std::int64_t session, const CompensationDemo& demo,
                             std::uint64_t seed);

}  // namespace ballbar::workflow
