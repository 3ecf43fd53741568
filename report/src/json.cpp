// SPDX-License-Identifier: MIT
// The report as data: schema "ballbar-report/2" (docs/report.md), in docs/cli.md's JSON vocabulary:
// units in the keys (angles in radians and arcseconds, so that no reader converts), an uncertainty as
// K_std next to K, an item's unit in `unit` where a list mixes them, absent values null.
#include <cmath>

#include "ballbar/analysis/rounding.hpp"
#include "ballbar/analysis/types.hpp"
#include "ballbar/report/report.hpp"
#include "format.hpp"

namespace ballbar::report {

namespace {

using nlohmann::json;

json opt(const std::optional<double>& v) {
    return v && std::isfinite(*v) ? json(*v) : json(nullptr);
}
json num(double v) {
    return std::isfinite(v) ? json(v) : json(nullptr);
}
json vec(const Vec3& v) {
    return json::array({num(v.x()), num(v.y()), num(v.z())});
}
/// `name`_rad, _deg and _arcsec (+ `suffix`) of an angle into `out` (null when it is absent).
void put_angle(json& out, const std::string& name, const std::optional<double>& rad, const std::string& suffix = "") {
    const bool known = rad && std::isfinite(*rad);
    out[name + "_rad" + suffix] = known ? json(*rad) : json(nullptr);
    out[name + "_deg" + suffix] = known ? json(analysis::rad_to_deg(*rad)) : json(nullptr);
    out[name + "_arcsec" + suffix] = known ? json(analysis::rad_to_arcsec(*rad)) : json(nullptr);
}
/// A text, or null when empty.
json text(const std::string& s) {
    return s.empty() ? json(nullptr) : json(s);
}
/// A count the model holds as an optional double.
json count(const std::optional<double>& v) {
    return v && std::isfinite(*v) ? json(static_cast<long long>(std::llround(*v))) : json(nullptr);
}
/// The report's screen units (µm, µm/m, °, …) as docs/cli.md's unit names (um, um_per_m, deg, …).
std::string unit_name(const std::string& screen) {
    static const std::pair<const char*, const char*> names[] = {
        {"µm", "um"}, {"µm/m", "um_per_m"}, {"µm/h", "um_per_h"},     {"ppm/K", "ppm_per_K"}, {"°", "deg"},
        {"Hz", "hz"}, {"µrad", "urad"},     {"µrad/h", "urad_per_h"}, {"µm/K", "um_per_K"}};
    for (const auto& [from, to] : names)
        if (screen == from) return to;
    return screen;
}
json range(const Range& r) {
    if (!r.present()) return nullptr;
    return {{"min", opt(r.min)}, {"mean", opt(r.mean)}, {"max", opt(r.max)}};
}
json nums(const std::vector<double>& v) {
    json a = json::array();
    for (double x : v) a.push_back(num(x));
    return a;
}

json header(const Header& h) {
    const auto& m = h.machine;
    json machine{
        {"name", m.name}, {"type", std::string(analysis::to_string(m.type))}, {"tool_ball_mm", vec(m.tool_ball_mm)}};
    if (m.type != analysis::MachineType::RRTTT) machine["a_pivot_mm"] = vec(m.a_pivot_mm);
    if (m.type == analysis::MachineType::TTTRR) machine["c_offset_mm"] = vec(m.c_offset_mm);
    return {{"session_id", h.session_id},
            {"session_name", text(h.session_name)},
            {"status", h.status},
            {"started_at", text(h.started_at)},
            {"finished_at", text(h.finished_at)},
            {"machine", machine},
            {"instrument",
             {{"model", text(h.instrument_model)},
              {"serial", text(h.instrument_serial)},
              {"firmware", text(h.instrument_firmware)},
              {"calibration_date", text(h.instrument_calibration_date)},
              {"calibrated_length_mm", opt(h.calibrated_length_mm)}}},
            {"operator", text(h.operator_name)},
            {"temperatures_C",
             {{"bar", range(h.bar_temp_C)}, {"machine", range(h.machine_temp_C)}, {"air", range(h.air_temp_C)}}},
            {"software_version", text(h.software_version)},
            {"notes", text(h.notes)}};
}

json circular(const Report& r) {
    if (!r.circular) return nullptr;
    const CircularTest& c = *r.circular;
    json runs = json::array();
    for (const auto& run : c.runs) {
        const bool model_drawn = run.model_angle_deg.size() == run.model_deviation_um.size();
        json j{{"direction", run.direction},
               {"start_deg", num(run.start_deg)},
               {"overshoot_deg", num(run.overshoot_deg)},
               {"data_arc_deg", num(run.data_arc_deg)},
               {"circularity_um", num(run.circularity_um)},
               {"radial_deviation_um", {{"max", num(run.radial_max_um)}, {"min", num(run.radial_min_um)}}},
               {"feed_in_end_s", opt(run.feed_in_end_s)},
               {"feed_in_lag_ms", opt(run.feed_in_lag_ms)},
               {"data_start_s", opt(run.data_start_s)},
               {"data_end_s", opt(run.data_end_s)},
               {"samples", count(run.samples)},
               {"polar",
                {{"angle_deg", nums(run.angle_deg)},
                 {"deviation_um", nums(run.deviation_um)},
                 {"model_angle_deg", nums(model_drawn ? run.model_angle_deg : std::vector<double>{})},
                 {"model_deviation_um", nums(model_drawn ? run.model_deviation_um : std::vector<double>{})}}}};
        j["pass"] = c.tolerance_um ? json(run.circularity_um <= *c.tolerance_um) : json(nullptr);
        runs.push_back(j);
    }
    json diags = json::array();
    for (const auto& d : c.diagnostics)
        diags.push_back({{"key", d.key},
                         {"name", d.name},
                         {"unit", unit_name(d.unit)},
                         {"value", num(d.value)},
                         {"value_std", opt(d.uncertainty)},
                         {"share_percent", opt(d.share_percent)},
                         {"rank", d.rank > 0 ? json(d.rank) : json(nullptr)},
                         {"action", text(d.action)}});
    json groups = json::array();
    for (const auto& g : c.unseparable)
        groups.push_back({{"keys", g.keys},
                          {"reason", g.reason},
                          {"combined_key", g.combined_key.empty() ? json(nullptr) : json(g.combined_key)},
                          {"combined_value", opt(g.combined_value)},
                          {"combined_value_std", opt(g.combined_uncertainty)}});
    json tolerance = nullptr;
    if (c.tolerance_um) {
        tolerance = {{"circularity_um", *c.tolerance_um}, {"source", c.tolerance_source}, {"pass", c.pass()}};
        tolerance["bidirectional_pass"] =
            c.bidirectional_um ? json(*c.bidirectional_um <= *c.tolerance_um) : json(nullptr);
    }
    // The instrument as the trace gave it: its JSON object, or null.
    json instrument = c.instrument.empty() ? json(nullptr) : json::parse(c.instrument, nullptr, false);
    if (instrument.is_discarded()) instrument = c.instrument;
    return {{"source", c.source},
            {"conditions",
             {{"plane", c.plane},
              {"radius_mm", num(c.radius_mm)},
              {"feed_mm_min", num(c.feed_mm_min)},
              {"feed_in_mm", num(c.feed_in_mm)},
              {"centre_mm", vec(c.centre_mm)},
              {"sample_rate_hz", opt(c.sample_rate_hz)},
              {"samples_used", count(c.samples_used)},
              {"bar_temp_C", range(c.bar_temp_C)},
              {"air_temp_C", range(c.air_temp_C)},
              {"instrument", instrument}}},
            {"runs", runs},
            {"bidirectional_circularity_um", opt(c.bidirectional_um)},
            {"hysteresis_um", opt(c.hysteresis_um)},
            {"radial_deviation_um", {{"max", num(c.radial_max_um)}, {"min", num(c.radial_min_um)}}},
            {"tolerance", tolerance},
            {"diagnostics", diags},
            {"not_detected", c.not_detected},
            {"unseparable", groups},
            {"residual_rms_um", opt(c.residual_rms_um)},
            {"mean_radius_um", opt(c.mean_radius_um)},
            {"mean_radius_um_std", opt(c.mean_radius_uncertainty_um)},
            {"polar_plot",
             {{"deviation_um_at_outer_ring", num(c.plot_deviation_um)},
              {"reference", "one least-squares circle for all runs (centre and radius removed)"},
              {"decimation", "first/min/max/last per angle column"},
              {"model",
               "the diagnosed effects of the path together (centre, mean radius, lag, every diagnosis but the "
               "vibration) about their own "
               "least-squares circle for all runs, min/max per 0.5° of the data arc"}}}};
}

}  // namespace

void set_ssm_tolerances(Report& report, std::optional<double> location_um, std::optional<double> angle_arcsec) {
    if (location_um) {
        report.location_tolerance_um = location_um;
        report.location_tolerance_source = "given";
        report.test_location_tolerance_um.clear();
    }
    if (angle_arcsec) {
        report.angle_tolerance_arcsec = angle_arcsec;
        report.angle_tolerance_source = "given";
        report.test_angle_tolerance_arcsec.clear();
    }
}

namespace {

/// A test's two locations are 2t and 2t + 1: the test of an orientation error from both, else −1.
int test_of(const OrientationError& o) {
    return o.from_location >= 0 && o.from_location % 2 == 0 && o.to_location == o.from_location + 1
               ? o.from_location / 2
               : -1;
}

std::optional<double> own_or(const std::vector<std::optional<double>>& own, int test, std::optional<double> machine) {
    if (test >= 0 && static_cast<std::size_t>(test) < own.size() && own[static_cast<std::size_t>(test)])
        return own[static_cast<std::size_t>(test)];
    return machine;
}

}  // namespace

std::optional<double> Report::location_tolerance_at(int location) const {
    return own_or(test_location_tolerance_um, location >= 0 ? location / 2 : -1, location_tolerance_um);
}

std::optional<double> Report::angle_tolerance_for(const OrientationError& o) const {
    return own_or(test_angle_tolerance_arcsec, test_of(o), angle_tolerance_arcsec);
}

SsmVerdict ssm_verdict(const Report& r) {
    SsmVerdict v;
    for (const auto& l : r.locations) {
        const auto tol = r.location_tolerance_at(l.location);
        if (!tol) continue;
        ++v.checked;
        if (!(l.error_um.norm() <= *tol))
            v.failures.push_back((l.label.empty() ? "L" + std::to_string(l.location) : l.label) + ": |ΔV| " +
                                 fixed(l.error_um.norm(), 2) + " µm > " + given(*tol) + " µm");
    }
    for (const auto& o : r.orientation) {
        const auto tol = r.angle_tolerance_for(o);
        if (!tol || !o.exact_rad) continue;
        ++v.checked;
        const double a = std::abs(analysis::rad_to_arcsec(*o.exact_rad));
        if (a <= *tol) continue;
        const int test = test_of(o);
        v.failures.push_back((test >= 0
                                  ? "test " + std::to_string(test + 1)
                                  : "L" + std::to_string(o.from_location) + " → L" + std::to_string(o.to_location)) +
                             ": " + o.symbol + " " + fixed(a, 2) + "″ > " + given(*tol) + "″");
    }
    v.judged = v.checked > 0;
    v.pass = v.judged && v.failures.empty();
    return v;
}

nlohmann::json to_json(const Report& r) {
    json j{{"schema", "ballbar-report/2"}, {"header", header(r.header)}};

    json& proc = j["procedure"] = json::array();
    for (const auto& e : r.procedure)
        proc.push_back({{"time_s", num(e.time_s)},
                        {"at", text(e.timestamp)},
                        {"kind", e.kind},
                        {"step", e.step},
                        {"detail", text(e.detail)}});

    json& locs = j["locations"] = json::array();
    for (const auto& l : r.locations) {
        const auto tol = r.location_tolerance_at(l.location);
        locs.push_back({{"location", l.location},
                        {"label", l.label},
                        {"position_mm", vec(l.position_mm)},
                        {"dV_um", vec(l.error_um)},
                        {"dV_um_std", vec(l.uncertainty_um)},
                        {"magnitude_um", num(l.error_um.norm())},
                        {"points", l.points},
                        {"residual_rms_um", opt(l.residual_rms_um)},
                        {"condition_number", opt(l.condition)},
                        {"tolerance_um", opt(tol)},
                        {"pass", tol ? json(l.error_um.norm() <= *tol) : json(nullptr)}});
    }

    json& ori = j["orientation"] = json::array();
    for (const auto& o : r.orientation) {
        json e{{"angle", o.symbol == "Δα" ? "d_alpha" : o.symbol == "Δβ" ? "d_beta" : "d_gamma"}, {"axis", o.axis}};
        put_angle(e, "commanded", o.commanded_rad);
        if (o.commanded_rad && std::isfinite(*o.commanded_rad)) {  // as the plan gave it: 30, not 29.999999999999996
            e["commanded_deg"] = analysis::decimal_round(analysis::rad_to_deg(*o.commanded_rad), 9);
            e["commanded_arcsec"] = analysis::decimal_round(analysis::rad_to_arcsec(*o.commanded_rad), 6);
        }
        put_angle(e, "first_order", o.first_order_rad);
        put_angle(e, "exact", o.exact_rad);
        put_angle(e, "exact", o.uncertainty_rad, "_std");
        e["from_location"] = o.from_location;
        e["to_location"] = o.to_location;
        const auto tol = r.angle_tolerance_for(o);
        e["tolerance_arcsec"] = opt(tol);
        e["pass"] = tol && o.exact_rad ? json(std::abs(analysis::rad_to_arcsec(*o.exact_rad)) <= *tol) : json(nullptr);
        ori.push_back(std::move(e));
    }

    j["bar_trace"] = {{"samples", r.trace.samples},     {"gaps", r.trace.gaps},
                      {"gap_s", r.trace.gap_s},         {"min_um", opt(r.trace.min_um)},
                      {"max_um", opt(r.trace.max_um)},  {"decimation", "first/min/max/last per column"},
                      {"time_s", nums(r.trace.time_s)}, {"displacement_um", nums(r.trace.displacement_um)}};

    json& caps = j["captures"] = json::array();
    for (const auto& c : r.captures)
        caps.push_back({{"start_s", num(c.start_s)},
                        {"end_s", num(c.end_s)},
                        {"location", c.location},
                        {"point", c.point},
                        {"mean_um", opt(c.mean_um)}});

    if (r.model) {
        const auto& m = *r.model;
        json params = json::array();
        for (const auto& p : m.parameters)
            params.push_back({{"name", p.name},
                              {"unit", unit_name(p.unit)},
                              {"value", num(p.value)},
                              {"value_std", opt(p.uncertainty)},
                              {"observability", opt(p.observability)},
                              {"note", text(p.note)}});
        j["model"] = {{"name", m.name},
                      {"parameters", params},
                      {"converged", m.converged ? json(*m.converged) : json(nullptr)},
                      {"iterations", m.iterations ? json(*m.iterations) : json(nullptr)},
                      {"residual_rms_before_um", opt(m.residual_rms_before_um)},
                      {"residual_rms_after_um", opt(m.residual_rms_after_um)},
                      {"condition_number", opt(m.condition)}};
    } else {
        j["model"] = nullptr;
    }

    json& disc = j["discovery"] = json::array();
    for (const auto& s : r.discovery)
        disc.push_back({{"effect", s.effect},
                        {"variable", s.variable},
                        {"variable_unit", text(unit_name(s.variable_unit))},
                        {"x", nums(s.x)},
                        {"before_um", nums(s.before_um)},
                        {"after_um", nums(s.after_um)},
                        {"rms_before_um", opt(s.rms_before_um)},
                        {"rms_after_um", opt(s.rms_after_um)},
                        {"accepted", s.accepted ? json(*s.accepted) : json(nullptr)},
                        {"binned", s.binned},
                        {"own_step", s.own_step},
                        {"note", text(s.note)}});

    json comp = json::array();
    for (const auto& c : r.compensation)
        comp.push_back({{"axis", c.axis}, {"before_um", num(c.before)}, {"after_um", num(c.after)}});
    j["compensation"] =
        r.compensation.empty() ? json(nullptr) : json{{"metric", text(r.compensation_metric)}, {"axes", comp}};
    // The SSM verdict (null: no tolerance, or a circular test, judged in "circular"."tolerance").
    if (const SsmVerdict v = ssm_verdict(r); v.judged)
        j["ssm_verdict"] = {{"pass", v.pass},
                            {"checked", v.checked},
                            {"failures", v.failures},
                            {"location_tolerance_um", opt(r.location_tolerance_um)},
                            {"location_tolerance_source", text(r.location_tolerance_source)},
                            {"angle_tolerance_arcsec", opt(r.angle_tolerance_arcsec)},
                            {"angle_tolerance_source", text(r.angle_tolerance_source)}};
    else
        j["ssm_verdict"] = nullptr;
    j["circular"] = circular(r);
    j["circular_note"] = text(r.circular_note);
    return j;
}

}  // namespace ballbar::report
