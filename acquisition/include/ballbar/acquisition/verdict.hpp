// SPDX-License-Identifier: MIT
// An SSM session's results judged against the tolerances (the plan test's own, else the machine file's): each
// location's |ΔV| against location_um, each measured orientation error (exact) against angle_arcsec.
// The same rule as the report's (report::set_ssm_tolerances): the value itself, its uncertainty shown
// beside it, not subtracted. docs/procedure.md.
#pragma once

#include <string>
#include <vector>

#include "ballbar/acquisition/interfaces.hpp"
#include "ballbar/acquisition/machine_file.hpp"
#include "ballbar/acquisition/plan.hpp"
#include "ballbar/analysis/types.hpp"

namespace ballbar::acquisition {

struct Check {
    int test = 0;          ///< 1-based, as the operator's screen numbers them
    std::string figure;    ///< "|ΔV1|", "|ΔV2|", "Δα", "Δβ", "Δγ"
    double value = 0;      ///< |ΔV| in µm, |angle| in arcsec
    double tolerance = 0;  ///< same unit
    std::string unit;      ///< "µm" or "″"
    bool pass() const { return value <= tolerance; }
};

struct SsmVerdict {
    std::vector<Check> checks;  ///< empty: no tolerance given, nothing judged
    bool judged() const { return !checks.empty(); }
    bool pass() const;  ///< every check within its tolerance (false when nothing was judged)
    /// "PASS: |ΔV| ≤ 20 µm at all 8 locations, angles ≤ 30″ (4 of 4)" or "FAIL: test 2 |ΔV2| 27.31 µm > 20 µm, …";
    /// "" when nothing was judged.
    std::string summary() const;
};

/// Judges each test against its own tolerances (the plan's `tests[].tolerances`), else the machine's:
/// `plan_tests` indexed by TestResult::test.
SsmVerdict judge_ssm(analysis::MachineType type, const Tolerances& machine, const std::vector<TestSpec>& plan_tests,
                     const std::vector<TestResult>& tests);

}  // namespace ballbar::acquisition
