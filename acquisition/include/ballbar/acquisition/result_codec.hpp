// SPDX-License-Identifier: MIT
// The results the guided SSM procedure stores with a session, one reader and one writer each
// (docs/storage.md, "Stored results"): kind "ssm" (one location's total position error and ΔV), kind
// "orientation" (one test's angle errors) and kind "acquisition.plan" (the machine and plan a session
// was measured with, what `measure --resume` takes up). The report, `sessions show`, the demos and any
// other front end read them through here, never by their keys.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

#include "ballbar/acquisition/interfaces.hpp"
#include "ballbar/acquisition/plan.hpp"

namespace ballbar::acquisition {

inline constexpr std::string_view kSsmResultKind = "ssm";
inline constexpr std::string_view kOrientationResultKind = "orientation";
inline constexpr std::string_view kPlanResultKind = "acquisition.plan";

/// A stored payload that is not the shape its kind has; the message names the key and the problem.
class ResultFormatError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// {"test", "step", "datum_mm", "e_exact_mm", "e_linear_mm", "e_std_mm", "dV_mm", "condition_number",
/// "n", "residual_rms_mm"?}. A condition number of +∞ (a degenerate layout) is written as null.
std::string location_to_json(const LocationResult& r);
/// Strict: every key of the writer's is required but residual_rms_mm; an unknown key, a vector that is
/// not three finite numbers, a count that is not a non-negative integer, is refused.
LocationResult location_from_json(std::string_view json);

/// {"test", "kind", "dV1_mm", "dV2_mm", "first_order", "exact", "std", "singular"?}; an orientation the
/// test could not solve (singular) is null.
std::string test_to_json(const TestResult& r);
TestResult test_from_json(std::string_view json);

/// {"machine": <machine file>, "plan": <plan file>} (docs/procedure.md).
std::string plan_to_json(const Plan& plan);
/// The plan again, made from the stored machine and plan files; PlanError when they are not a plan
/// ballbar can measure (the files' readers and make_plan check them).
Plan plan_from_json(std::string_view json);

}  // namespace ballbar::acquisition
