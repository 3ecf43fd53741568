// SPDX-License-Identifier: MIT
#include "ballbar/acquisition/plan.hpp"

#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

#include "ballbar/analysis/kinematics.hpp"
#include "json_util.hpp"

namespace ballbar::acquisition {

using nlohmann::json;
using namespace ballbar::analysis;
namespace limits = ballbar::analysis::limits;

std::string_view to_string(TestKind kind) {
    switch (kind) {
        case TestKind::BothAxes:
            return "BothAxes";
        case TestKind::SpindleBeta:
            return "SpindleBeta";
        case TestKind::TableAlpha:
            return "TableAlpha";
    }
    return "?";
}

namespace {

constexpr std::string_view kPlanFormat = "ballbar-plan/1";

/// Direction of the bar's cone axis for a step: from the table ball towards the spindle. For a
/// spindle-carried rotary head that is the tool's direction (ball to pivot); otherwise +Z.
Vec3 cone_axis(const MachineGeometry& geom, const Pose& rotary) {
    if (geom.type == MachineType::TTTRR || geom.tool_ball_mm.norm() == 0) return Vec3::UnitZ();
    Pose at = rotary;
    at.X_mm = at.Y_mm = at.Z_mm = 0;
    const Vec3 tool = nominal_tool_ball(geom, at);  // pivot at origin: the rotated tool vector
    return (-tool).normalized();
}

std::string format_point(int test, int step, int point) {
    std::ostringstream os;
    os << "test " << test + 1 << ", step " << step << ", point " << point + 1;
    return os.str();
}

}  // namespace

std::string check_travel(const MachineFile& machine, const Pose& pose) {
    const double values[kAxisCount] = {pose.X_mm, pose.Y_mm, pose.Z_mm, pose.A_rad, pose.B_rad, pose.C_rad};
    const RotaryAxes rot = rotary_axes(machine.geometry.type);
    for (int i = 0; i < kAxisCount; ++i) {
        const auto a = static_cast<Axis>(i);
        const bool rotary = i >= 3;
        if (rotary && axis_name(a)[0] != rot.first && axis_name(a)[0] != rot.second) continue;
        const AxisRange& r = machine.range(a);
        const double v = values[i];
        if (v >= r.min - 1e-9 && v <= r.max + 1e-9) continue;
        const double scale = rotary ? rad_to_deg(1.0) : 1.0;
        const char* unit = rotary ? " deg" : " mm";
        std::ostringstream os;
        os << axis_name(a) << " = " << v * scale << unit << " is outside the travel [" << r.min * scale << ", "
           << r.max * scale << "]" << unit;
        return os.str();
    }
    return {};
}

void check_plan_spec(const PlanSpec& spec, const std::string& what) {
    detail::require_above(what, "bar_length_mm", spec.bar_length_mm, 0, limits::kLength_mm, "mm");
    const CaptureSettings& c = spec.capture;
    const std::string cw = what + ": capture";
    detail::require_in(cw, "window_s", c.window_s, kMinWindow_s, kMaxWindow_s, "s");
    detail::require_above(cw, "max_std_um", c.max_std_mm * 1e3, 0, 1000, "um");
    detail::require_above(cw, "max_drift_um", c.max_drift_mm * 1e3, 0, 1000, "um");
    detail::require_above(cw, "tolerance_mm", c.tolerance_mm, 0, 1, "mm");
    if (const std::string why = limits::check_integer_in(c.retries, 0, kMaxRetries); !why.empty())
        throw PlanError(cw + ": retries " + why);
    detail::require_in(what, "max_condition", spec.max_condition, 1, 1e6, "");
    // One window to settle, one to average: a shorter dwell can never give a point.
    if (!(spec.dwell_s >= 2 * c.window_s && spec.dwell_s <= kMaxPlanDwell_s)) {
        std::ostringstream os;
        os << what << ": dwell_s = " << limits::number_text(spec.dwell_s) << " s: it must be at least two capture "
           << "windows (2 x capture.window_s = " << 2 * c.window_s << " s: one to settle, one to average) and at most "
           << kMaxPlanDwell_s << " s";
        throw PlanError(os.str());
    }
    for (std::size_t t = 0; t < spec.tests.size(); ++t) {
        const std::string tw = what + ": tests[" + std::to_string(t) + "]";
        detail::require_position(tw, "socket_mm", spec.tests[t].socket_mm);
        for (const double r : {spec.tests[t].first_rad, spec.tests[t].second_rad})
            detail::require_in(tw, "rotation_deg", rad_to_deg(r), -limits::kRotation_deg, limits::kRotation_deg, "deg");
    }
}

Plan make_plan(const MachineFile& machine, const PlanSpec& spec) {
    if (spec.tests.empty()) throw PlanError("plan: no tests to run");
    check_plan_spec(spec, "plan");
    const MachineGeometry& geom = machine.geometry;
    Plan plan;
    plan.machine = machine;
    plan.spec = spec;
    for (int t = 0; t < static_cast<int>(spec.tests.size()); ++t) {
        const TestSpec& test = spec.tests[static_cast<std::size_t>(t)];
        if (test.first_rad == 0 && test.second_rad == 0)
            throw PlanError("plan: test " + std::to_string(t + 1) + " has no rotation (both angles are zero)");
        for (int step = 1; step <= 2; ++step) {
            Pose rot;
            if (step == 2) {
                rot.A_rad = test.first_rad;
                if (rotary_axes(geom.type).second == 'B')
                    rot.B_rad = test.second_rad;
                else
                    rot.C_rad = test.second_rad;
            }
            const Vec3 datum = nominal_table_ball(geom, rot, test.socket_mm);
            const Vec3 axis = cone_axis(geom, rot);
            const analysis::Layout layout = make_layout(spec.layout, datum, spec.bar_length_mm, axis);
            const double cond = layout.condition_number;
            if (cond > spec.max_condition) {
                std::ostringstream os;
                os << "plan: test " << t + 1 << " step " << step << ": layout condition number " << cond
                   << " exceeds the limit " << spec.max_condition;
                throw PlanError(os.str());
            }
            plan.points_per_step = static_cast<int>(layout.points_mm.size());
            for (int p = 0; p < plan.points_per_step; ++p) {
                PlannedPoint pt;
                pt.test = t;
                pt.step = step;
                pt.point = p;
                pt.socket_mm = test.socket_mm;
                pt.datum_mm = datum;
                pt.tool_ball_mm = layout.points_mm[static_cast<std::size_t>(p)];
                pt.pose = command_for_tool_ball(geom, rot, pt.tool_ball_mm);
                pt.nominal_mm = nominal_length(geom, pt.pose, test.socket_mm);
                if (const std::string why = check_travel(machine, pt.pose); !why.empty())
                    throw PlanError("plan: " + format_point(t, step, p) + ": " + why);
                plan.points.push_back(pt);
            }
        }
    }
    return plan;
}

// ---- plan file -------------------------------------------------------------------------------------

namespace {

TestSpec parse_test(const json& jt, MachineType type, int index) {
    const std::string what = "plan file: tests[" + std::to_string(index) + "]";
    if (!jt.is_object()) throw PlanError(what + " must be an object");
    detail::only_keys(jt, what, {"socket_mm", "rotation_deg", "tolerances"});
    TestSpec t;
    if (!jt.contains("socket_mm")) throw PlanError(what + ": missing key \"socket_mm\"");
    t.socket_mm = detail::to_vec3(jt.at("socket_mm"), "socket_mm", what);
    if (!jt.contains("rotation_deg") || !jt.at("rotation_deg").is_object())
        throw PlanError(what + ": \"rotation_deg\" must be an object such as {\"A\": 10, \"C\": 30}");
    const RotaryAxes axes = rotary_axes(type);
    for (auto it = jt.at("rotation_deg").begin(); it != jt.at("rotation_deg").end(); ++it) {
        if (!it.value().is_number()) throw PlanError(what + ": rotation_deg." + it.key() + " must be a number");
        const double v = deg_to_rad(detail::require_in(what, "rotation_deg." + it.key(), it.value().get<double>(),
                                                       -limits::kRotation_deg, limits::kRotation_deg, "deg"));
        if (it.key().size() == 1 && it.key()[0] == axes.first)
            t.first_rad = v;
        else if (it.key().size() == 1 && it.key()[0] == axes.second)
            t.second_rad = v;
        else
            throw PlanError(what + ": a " + std::string(to_string(type)) + " turns " + axes.first + " and " +
                            axes.second + ", not \"" + it.key() + "\"");
    }
    if (type == MachineType::RTTTR) {
        if (t.first_rad != 0 && t.second_rad != 0)
            throw PlanError(what + ": an RTTTR test measures Δβ (B, spindle) or Δα (A, table) alone; give one angle");
        t.kind = t.second_rad != 0 ? TestKind::SpindleBeta : TestKind::TableAlpha;
    }
    if (jt.contains("tolerances")) t.tolerances = detail::parse_tolerances(jt.at("tolerances"), what, false);
    return t;
}

PointFailureAction parse_failure_action(const std::string& s) {
    if (s == "retry") return PointFailureAction::Retry;
    if (s == "accept") return PointFailureAction::Accept;
    if (s == "abort") return PointFailureAction::Abort;
    throw PlanError("plan file: answers.on_point_failure \"" + s + "\" is not retry, accept or abort");
}

std::string_view failure_action_name(PointFailureAction a) {
    return a == PointFailureAction::Retry ? "retry" : a == PointFailureAction::Accept ? "accept" : "abort";
}

}  // namespace

PlanSpec parse_plan_file(std::string_view json_text, MachineType type) {
    const json j = detail::parse_json(json_text, "plan file");
    if (!j.is_object()) throw PlanError("plan file: expected a JSON object");
    detail::only_keys(j, "plan file",
                      {"format", "bar_length_mm", "layout", "dwell_s", "max_condition", "tests", "capture", "answers"});
    if (j.contains("format") && j.at("format") != kPlanFormat)
        throw PlanError("plan file: format must be \"" + std::string(kPlanFormat) + "\"");
    PlanSpec s;
    if (j.contains("bar_length_mm")) s.bar_length_mm = detail::get_number(j, "bar_length_mm", "plan file");
    if (j.contains("layout")) {
        const std::string text = detail::get_string(j, "layout", "plan file");
        const auto kind = parse_layout_kind(text);
        if (!kind) throw PlanError("plan file: layout \"" + text + "\" is not cube-corner, 4-point or 6-point");
        s.layout = *kind;
    }
    if (j.contains("dwell_s")) s.dwell_s = detail::get_number(j, "dwell_s", "plan file");
    if (j.contains("max_condition")) s.max_condition = detail::get_number(j, "max_condition", "plan file");
    if (!j.contains("tests") || !j.at("tests").is_array() || j.at("tests").empty())
        throw PlanError("plan file: \"tests\" must be a non-empty array");
    int i = 0;
    for (const json& jt : j.at("tests")) s.tests.push_back(parse_test(jt, type, i++));
    if (j.contains("capture")) {
        const json& c = j.at("capture");
        const std::string w = "plan file: capture";
        if (!c.is_object()) throw PlanError(w + " must be an object");
        detail::only_keys(c, w, {"mode", "window_s", "max_std_um", "max_drift_um", "tolerance_mm", "retries"});
        if (c.contains("mode")) {
            const std::string mode = detail::get_string(c, "mode", w);
            if (mode != "auto" && mode != "manual") throw PlanError(w + ": mode must be auto or manual");
            s.capture.manual = mode == "manual";
        }
        if (c.contains("window_s")) s.capture.window_s = detail::get_number(c, "window_s", w);
        if (c.contains("max_std_um")) s.capture.max_std_mm = detail::get_number(c, "max_std_um", w) * 1e-3;
        if (c.contains("max_drift_um")) s.capture.max_drift_mm = detail::get_number(c, "max_drift_um", w) * 1e-3;
        if (c.contains("tolerance_mm")) s.capture.tolerance_mm = detail::get_number(c, "tolerance_mm", w);
        if (c.contains("retries")) {
            const double r = detail::get_number(c, "retries", w);
            if (const std::string why = limits::check_integer_in(r, 0, kMaxRetries); !why.empty())
                throw PlanError(w + ": retries " + why);
            s.capture.retries = static_cast<int>(r);
        }
    }
    if (j.contains("answers")) {
        const json& a = j.at("answers");
        const std::string w = "plan file: answers";
        if (!a.is_object()) throw PlanError(w + " must be an object");
        detail::only_keys(a, w, {"operator", "confirm_setup", "accept_results", "on_point_failure"});
        if (a.contains("operator")) s.answers.operator_name = detail::get_string(a, "operator", w);
        for (auto [key, into] : {std::pair{"confirm_setup", &s.answers.confirm_setup},
                                 std::pair{"accept_results", &s.answers.accept_results}}) {
            if (!a.contains(key)) continue;
            if (!a.at(key).is_boolean()) throw PlanError(w + ": " + key + " must be true or false");
            *into = a.at(key).get<bool>();
        }
        if (a.contains("on_point_failure"))
            s.answers.on_point_failure = parse_failure_action(detail::get_string(a, "on_point_failure", w));
    }
    check_plan_spec(s, "plan file");
    return s;
}

std::string write_plan_file(const PlanSpec& s, MachineType type) {
    json j;
    j["format"] = kPlanFormat;
    j["bar_length_mm"] = s.bar_length_mm;
    j["layout"] = std::string(to_string(s.layout));
    j["dwell_s"] = s.dwell_s;
    j["max_condition"] = s.max_condition;
    const RotaryAxes axes = rotary_axes(type);
    json tests = json::array();
    for (const TestSpec& t : s.tests) {
        json rot = json::object();
        rot[std::string(1, axes.first)] = rad_to_deg(t.first_rad);
        rot[std::string(1, axes.second)] = rad_to_deg(t.second_rad);
        json test = {{"socket_mm", {t.socket_mm.x(), t.socket_mm.y(), t.socket_mm.z()}}, {"rotation_deg", rot}};
        if (t.tolerances.any()) test["tolerances"] = detail::tolerances_json(t.tolerances);
        tests.push_back(test);
    }
    j["tests"] = tests;
    j["capture"] = {{"mode", s.capture.manual ? "manual" : "auto"}, {"window_s", s.capture.window_s},
                    {"max_std_um", s.capture.max_std_mm * 1e3},     {"max_drift_um", s.capture.max_drift_mm * 1e3},
                    {"tolerance_mm", s.capture.tolerance_mm},       {"retries", s.capture.retries}};
    j["answers"] = {{"operator", s.answers.operator_name},
                    {"confirm_setup", s.answers.confirm_setup},
                    {"accept_results", s.answers.accept_results},
                    {"on_point_failure", std::string(failure_action_name(s.answers.on_point_failure))}};
    return j.dump(2) + "\n";
}

PlanSpec default_plan(const MachineFile& machine) {
    PlanSpec s;
    auto add = [&](Vec3 socket, double first_deg, double second_deg, TestKind kind) {
        s.tests.push_back({socket, deg_to_rad(first_deg), deg_to_rad(second_deg), kind, {}});
    };
    switch (machine.geometry.type) {
        case MachineType::RRTTT:
            // Seed Table 1's location: the ball at (−50, −15, 250), the socket one bar length below.
            for (auto [a, b] : {std::pair{30.0, 0.0}, {0.0, 40.0}, {45.0, 60.0}, {30.0, 60.0}})
                add(Vec3(-50, -15, 150), a, b, TestKind::BothAxes);
            break;
        case MachineType::TTTRR:
            // Seed Table 2's four rotation pairs (α/γ) at one socket.
            for (auto [a, c] : {std::pair{0.0, 30.0}, {15.0, 0.0}, {10.0, 30.0}, {10.0, 45.0}})
                add(Vec3(-49.275, -14.312, -77.777), a, c, TestKind::BothAxes);
            break;
        case MachineType::RTTTR:
            add(Vec3(-30, 20, 60), 0, 30.0, TestKind::SpindleBeta);
            add(Vec3(-30, 20, 60), 0, -20.0, TestKind::SpindleBeta);
            add(Vec3(-30, 20, 60), 15.0, 0, TestKind::TableAlpha);
            add(Vec3(-30, 20, 60), -10.0, 0, TestKind::TableAlpha);
            break;
    }
    return s;
}

std::string point_label(const PlannedPoint& p) {
    return "test " + std::to_string(p.test + 1) + " step " + std::to_string(p.step) + " point " +
           std::to_string(p.point + 1);
}

}  // namespace ballbar::acquisition
