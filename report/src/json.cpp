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

json circular(const Report& r) {
    if (!r.circular) return nullptr;
    const CircularTest& c = *r.circular;
    json runs = json::array();
    for (const auto& run : c.runs) {
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
               {"samples", opt(run.samples)},
               {"polar", {{"angle_deg", nums(run.angle_deg)}, {"deviation_um", nums(run.deviation_um)}}}};
        if (c.tolerance_um) j["pass"] = run.circularity_um <= *c.tolerance_um;
        runs.push_back(j);
    }
    json diags = json::array();
    for (const auto& d : c.diagnostics)
        diags.push_back({{"key", d.key},
                         {"name", d.name},
                         {"unit", d.unit},
                         {"value", num(d.value)},
                         {"uncertainty", opt(d.uncertainty)},
                         {"share_percent", opt(d.share_percent)},
                         {"rank", d.rank > 0 ? json(d.rank) : json(nullptr)}});
    json groups = json::array();
    for (const auto& g : c.unseparable)
        groups.push_back({{"keys", g.keys},
                          {"reason", g.reason},
                          {"combined_key", g.combined_key.empty() ? json(nullptr) : json(g.combined_key)},
                          {"combined_value", opt(g.combined_value)},
                          {"combined_uncertainty", opt(g.combined_uncertainty)}});
    json tolerance = nullptr;
    if (c.tolerance_um) {
        tolerance = {{"circularity_um", *c.tolerance_um}, {"source", c.tolerance_source}, {"pass", c.pass()}};
        if (c.bidirectional_um) tolerance["bidirectional_pass"] = *c.bidirectional_um <= *c.tolerance_um;
    }
    return {
        {"source", c.source},
        {"conditions",
         {{"plane", c.plane},
          {"radius_mm", num(c.radius_mm)},
          {"feed_mm_min", num(c.feed_mm_min)},
          {"feed_in_mm", num(c.feed_in_mm)},
          {"centre_mm", vec(c.centre_mm)},
          {"sample_rate_hz", opt(c.sample_rate_hz)},
          {"samples_used", opt(c.samples_used)},
          {"bar_temp_C", range(c.bar_temp_C)},
          {"air_temp_C", range(c.air_temp_C)},
          {"instrument", c.instrument}}},
        {"runs", runs},
        {"bidirectional_circularity_um", opt(c.bidirectional_um)},
        {"radial_deviation_um", {{"max", num(c.radial_max_um)}, {"min", num(c.radial_min_um)}}},
        {"tolerance", tolerance},
        {"diagnostics", diags},
        {"not_detected", c.not_detected},
        {"unseparable", groups},
        {"residual_rms_um", opt(c.residual_rms_um)},
        {"mean_radius_um", {{"value", opt(c.mean_radius_um)}, {"std_uncertainty", opt(c.mean_radius_uncertainty_um)}}},
        {"polar_plot",
         {{"deviation_um_at_outer_ring", num(c.plot_deviation_um)},
          {"reference", "one least-squares circle for all runs (centre and radius removed)"},
          {"decimation", "first/min/max/last per angle column"}}}};
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
    j["circular"] = circular(r);
    if (!r.circular_note.empty()) j["circular_note"] = r.circular_note;
    return j;
}

}  // namespace ballbar::report
