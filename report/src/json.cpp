// SPDX-License-Identifier: MIT
// The report as data: schema "ballbar-report/1" (docs/report.md). Angles are given in radians,
// degrees and arcseconds so that no reader converts; absent values are null.
#include <cmath>

#include "ballbar/analysis/types.hpp"
#include "ballbar/report/report.hpp"

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
json angle(const std::optional<double>& rad) {
    if (!rad || !std::isfinite(*rad)) return nullptr;
    return {{"rad", *rad}, {"deg", analysis::rad_to_deg(*rad)}, {"arcsec", analysis::rad_to_arcsec(*rad)}};
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
            {"session_name", h.session_name},
            {"status", h.status},
            {"started_at", h.started_at},
            {"finished_at", h.finished_at},
            {"machine", machine},
            {"instrument",
             {{"model", h.instrument_model},
              {"serial", h.instrument_serial},
              {"firmware", h.instrument_firmware},
              {"calibration_date", h.instrument_calibration_date},
              {"calibrated_length_mm", opt(h.calibrated_length_mm)}}},
            {"operator", h.operator_name},
            {"temperatures_C",
             {{"bar", range(h.bar_temp_C)}, {"machine", range(h.machine_temp_C)}, {"air", range(h.air_temp_C)}}},
            {"software_version", h.software_version},
            {"notes", h.notes}};
}

}  // namespace

nlohmann::json to_json(const Report& r) {
    json j{{"schema", "ballbar-report/1"}, {"header", header(r.header)}};

    json& proc = j["procedure"] = json::array();
    for (const auto& e : r.procedure)
        proc.push_back({{"time_s", num(e.time_s)},
                        {"timestamp", e.timestamp},
                        {"kind", e.kind},
                        {"step", e.step},
                        {"detail", e.detail}});

    json& locs = j["locations"] = json::array();
    for (const auto& l : r.locations)
        locs.push_back({{"location", l.location},
                        {"label", l.label},
                        {"position_mm", vec(l.position_mm)},
                        {"error_um", vec(l.error_um)},
                        {"uncertainty_um", vec(l.uncertainty_um)},
                        {"magnitude_um", num(l.error_um.norm())},
                        {"points", l.points},
                        {"residual_rms_um", opt(l.residual_rms_um)},
                        {"condition", opt(l.condition)}});

    json& ori = j["orientation"] = json::array();
    for (const auto& o : r.orientation)
        ori.push_back({{"symbol", o.symbol},
                       {"axis", o.axis},
                       {"commanded", angle(o.commanded_rad)},
                       {"first_order", angle(o.first_order_rad)},
                       {"exact", angle(o.exact_rad)},
                       {"uncertainty", angle(o.uncertainty_rad)},
                       {"from_location", o.from_location},
                       {"to_location", o.to_location}});

    j["bar_trace"] = {{"samples", r.trace.samples},     {"min_um", opt(r.trace.min_um)},
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
                              {"unit", p.unit},
                              {"value", num(p.value)},
                              {"uncertainty", opt(p.uncertainty)},
                              {"observability", opt(p.observability)},
                              {"note", p.note}});
        j["model"] = {{"name", m.name},
                      {"parameters", params},
                      {"converged", m.converged ? json(*m.converged) : json(nullptr)},
                      {"iterations", m.iterations ? json(*m.iterations) : json(nullptr)},
                      {"residual_rms_before_um", opt(m.residual_rms_before_um)},
                      {"residual_rms_after_um", opt(m.residual_rms_after_um)},
                      {"condition", opt(m.condition)}};
    } else {
        j["model"] = nullptr;
    }

    json& disc = j["discovery"] = json::array();
    for (const auto& s : r.discovery)
        disc.push_back({{"effect", s.effect},
                        {"variable", s.variable},
                        {"variable_unit", s.variable_unit},
                        {"x", nums(s.x)},
                        {"before_um", nums(s.before_um)},
                        {"after_um", nums(s.after_um)},
                        {"rms_before_um", opt(s.rms_before_um)},
                        {"rms_after_um", opt(s.rms_after_um)},
                        {"accepted", s.accepted ? json(*s.accepted) : json(nullptr)},
                        {"binned", s.binned},
                        {"own_step", s.own_step},
                        {"note", s.note}});

    json comp = json::array();
    for (const auto& c : r.compensation)
        comp.push_back({{"axis", c.axis}, {"unit", c.unit}, {"before", num(c.before)}, {"after", num(c.after)}});
    j["compensation"] = {{"metric", r.compensation_metric}, {"axes", comp}};
    return j;
}

}  // namespace ballbar::report
