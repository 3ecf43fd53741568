// SPDX-License-Identifier: MIT
// The measurement plan: which two-step tests a session runs (socket position and rotation pair), how
// each location's SSM points are laid out, how points are captured, and the answers a non-interactive
// run gives. `make_plan` turns it into the ordered list of commanded poses, checked against the
// machine's travel and the SSM conditioning limit. docs/procedure.md documents the plan file.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "ballbar/acquisition/machine_file.hpp"
#include "ballbar/analysis/layout.hpp"
#include "ballbar/analysis/orientation.hpp"
#include "ballbar/analysis/types.hpp"

namespace ballbar::acquisition {

/// What a test's rotation measures.
enum class TestKind {
    BothAxes,     ///< RRTTT (Δα, Δβ of the head) and TTTRR (Δα, Δγ of the table)
    SpindleBeta,  ///< RTTTR: the spindle turns about B, socket on the bed (table at A = 0): Δβ
    TableAlpha,   ///< RTTTR: the table turns about A, socket on the turning table: Δα
};
/// The kind's one spelling, on the screen, in every `--json` and in the stored `orientation` results
/// (docs/report.md): "BothAxes", "SpindleBeta", "TableAlpha".
std::string_view to_string(TestKind kind);
/// The angles a test of `kind` on a machine of `type` determines (analysis::measured_angles).
inline analysis::MeasuredAngles measured_angles(analysis::MachineType type, TestKind kind) {
    return analysis::measured_angles(type, kind == TestKind::SpindleBeta);
}

/// One two-step test: step 1 at the rotary start (0, 0), step 2 after the rotation pair.
struct TestSpec {
    analysis::Vec3 socket_mm = analysis::Vec3::Zero();  ///< socket in the table frame (RRTTT: machine frame)
    double first_rad = 0;                               ///< the type's first rotary axis: A
    double second_rad = 0;                              ///< the second: B (RRTTT, RTTTR) or C (TTTRR)
    TestKind kind = TestKind::BothAxes;
    /// This test's own tolerances (plan file `tests[].tolerances`: location_um, angle_arcsec), each in
    /// place of the machine file's for this test only; none given: the machine's.
    Tolerances tolerances;
};

enum class PointFailureAction { Retry, Accept, Abort };

struct CaptureSettings {
    bool manual = false;          ///< the operator confirms each point instead of dwell detection
    double window_s = 0.5;        ///< averaging window of one point
    double max_std_mm = 0.002;    ///< quality: standard deviation of the window's samples
    double max_drift_mm = 0.002;  ///< quality: drift (fitted slope × window length)
    double tolerance_mm = 0.5;    ///< reading vs. the point's expected length (the bar's range is ±1 mm)
    int retries = 2;              ///< automatic re-captures of a failed point before asking the operator
};

/// Answers of a non-interactive run (`--non-interactive`).
struct Answers {
    std::string operator_name;
    bool confirm_setup = true;
    bool accept_results = true;
    PointFailureAction on_point_failure = PointFailureAction::Abort;
};

struct PlanSpec {
    double bar_length_mm = 100;
    analysis::LayoutKind layout = analysis::LayoutKind::CubeCorner;
    double dwell_s = 1.5;       ///< G4 at each point; must exceed the capture window
    double max_condition = 10;  ///< refuse layouts worse than this
    std::vector<TestSpec> tests;
    CaptureSettings capture;
    Answers answers;
};

/// The plan's ranges (docs/procedure.md, "The plan file"): capture windows of 0.01–60 s, a dwell of
/// at least two windows and at most an hour, at most 100 retries.
inline constexpr double kMinWindow_s = 0.01, kMaxWindow_s = 60, kMaxPlanDwell_s = 3600;
inline constexpr int kMaxRetries = 100;

/// Refuses a spec with a value outside its range, naming the field after `what` ("plan file: dwell_s
/// = 0.6 s: it must be at least two capture windows ..."). Throws PlanError.
void check_plan_spec(const PlanSpec& spec, const std::string& what);

/// Parses a plan file for a machine of `type` (the rotation keys depend on it). Throws PlanError.
PlanSpec parse_plan_file(std::string_view json_text, analysis::MachineType type);
std::string write_plan_file(const PlanSpec& spec, analysis::MachineType type);
/// The seed's Table 2 style default: one socket, four rotation pairs (RTTTR: two Δβ and two Δα tests).
PlanSpec default_plan(const MachineFile& machine);

struct PlannedPoint {
    int test = 0;
    int step = 1;                                          ///< 1: rotary axes at start; 2: after the rotation pair
    int point = 0;                                         ///< index within the step
    analysis::Pose pose;                                   ///< commanded axes
    analysis::Vec3 socket_mm = analysis::Vec3::Zero();     ///< socket, table frame
    analysis::Vec3 datum_mm = analysis::Vec3::Zero();      ///< nominal table ball, machine frame
    analysis::Vec3 tool_ball_mm = analysis::Vec3::Zero();  ///< nominal tool ball, machine frame
    double nominal_mm = 0;                                 ///< expected bar length
};

/// "test 2 step 1 point 3": a point as the operator counts (tests and points from 1).
std::string point_label(const PlannedPoint& p);

struct Plan {
    MachineFile machine;
    PlanSpec spec;
    int points_per_step = 3;
    std::vector<PlannedPoint> points;  ///< test by test, step 1 then step 2, in capture order

    std::size_t index(int test, int step, int point) const {
        return static_cast<std::size_t>((test * 2 + (step - 1)) * points_per_step + point);
    }
    int test_count() const { return static_cast<int>(spec.tests.size()); }
};

/// Plans every point: datum from the socket and rotation, points at the bar length in the layout's
/// directions (cone around the spindle's direction), commanded poses via command_for_tool_ball.
/// Throws PlanError naming the test, step, point and axis when a pose leaves the travel, or when a
/// location's condition number exceeds spec.max_condition.
Plan make_plan(const MachineFile& machine, const PlanSpec& spec);

/// Checks one pose against the travel; returns an empty string or the problem ("A = 130° beyond 120°").
std::string check_travel(const MachineFile& machine, const analysis::Pose& pose);

}  // namespace ballbar::acquisition
