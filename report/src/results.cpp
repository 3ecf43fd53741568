// SPDX-License-Identifier: MIT
#include "ballbar/report/results.hpp"

#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include "ballbar/acquisition/result_codec.hpp"
#include "ballbar/analysis/orientation.hpp"
#include "ballbar/analysis/types.hpp"
#include "ballbar/storage/compensation_codec.hpp"
#include "ballbar/storage/discovery_codec.hpp"
#include "ballbar/storage/identification_codec.hpp"
#include "ballbar/storage/machine_json.hpp"
#include "circular.hpp"

namespace ballbar::report {

namespace {

using nlohmann::json;

[[noreturn]] void bad(std::string_view kind, const std::string& key, const std::string& what) {
    throw ReportError("result \"" + std::string(kind) + "\": \"" + key + "\" " + what);
}

const json* find(const json& j, const char* key) {
    if (!j.is_object()) return nullptr;
    const auto it = j.find(key);
    return it == j.end() || it->is_null() ? nullptr : &*it;
}

std::optional<double> opt_num(std::string_view kind, const json& j, const char* key) {
    const json* v = find(j, key);
    if (!v) return std::nullopt;
    if (!v->is_number()) bad(kind, key, "must be a number");
    return v->get<double>();
}
std::string opt_str(std::string_view kind, const json& j, const char* key) {
    const json* v = find(j, key);
    if (!v) return {};
    if (!v->is_string()) bad(kind, key, "must be a string");
    return v->get<std::string>();
}
// The procedure's results are read by their codec (acquisition/result_codec.hpp): strict, one owner.
void add_ssm(Report& r, const json& p) {
    const acquisition::LocationResult x = acquisition::location_from_json(p.dump());
    LocationError l;
    l.location = x.test * 2 + x.step - 1;
    // Numbered as the CLI numbers them (measure's prompts, sessions show): test and step from 1.
    l.label =
        "test " + std::to_string(x.test + 1) + (x.step == 1 ? " step 1, before rotation" : " step 2, after rotation");
    l.error_um = x.dV_mm * 1000.0;
    l.uncertainty_um = x.ssm.std_mm * 1000.0;
    l.position_mm = x.datum_mm;
    l.points = static_cast<int>(x.ssm.n);
    if (x.ssm.residual_rms_mm) l.residual_rms_um = *x.ssm.residual_rms_mm * 1000.0;
    if (std::isfinite(x.ssm.condition_number)) l.condition = x.ssm.condition_number;
    r.locations.push_back(l);
}

void add_orientation(Report& r, const json& p) {
    const acquisition::TestResult t = acquisition::test_from_json(p.dump());
    struct Angle {
        const char* symbol;
        const char* axis;
        double analysis::OrientationErrors::*member;
    };
    std::vector<Angle> angles;
    const analysis::MeasuredAngles measured = acquisition::measured_angles(r.header.machine.type, t.kind);
    if (measured.alpha) angles.push_back({"Δα", "A", &analysis::OrientationErrors::d_alpha_rad});
    if (measured.beta) angles.push_back({"Δβ", "B", &analysis::OrientationErrors::d_beta_rad});
    if (measured.gamma) angles.push_back({"Δγ", "C", &analysis::OrientationErrors::d_gamma_rad});
    auto value = [](const std::optional<analysis::OrientationErrors>& e, double analysis::OrientationErrors::*m) {
        return e ? std::optional<double>((*e).*m) : std::nullopt;
    };
    for (const auto& a : angles) {
        OrientationError o;
        o.symbol = a.symbol;
        o.axis = a.axis;
        o.first_order_rad = value(t.orientation.first_order, a.member);
        o.exact_rad = value(t.orientation.exact, a.member);
        o.uncertainty_rad = value(t.std_rad, a.member);
        o.from_location = t.test * 2;
        o.to_location = t.test * 2 + 1;
        r.orientation.push_back(o);
    }
}

/// Internal units of the analysis (mm, rad, …) to the units the report shows, and the factor.
std::pair<double, std::string> display_unit(const std::string& unit) {
    if (unit == "mm") return {1000.0, "µm"};
    if (unit == "rad") return {analysis::rad_to_arcsec(1.0), "arcsec"};
    if (unit == "mm/mm" || unit == "mm_per_mm") return {1e6, "µm/m"};
    if (unit == "mm/h" || unit == "mm_per_h") return {1000.0, "µm/h"};
    if (unit == "1/K" || unit == "per_K") return {1e6, "ppm/K"};
    return {1.0, unit};
}

// `identify`'s result, read by its codec (storage/identification_codec.hpp). The model's name and
// version are the stored model's (build.cpp); a result given alone has none.
void add_identification(Report& r, const json& p) {
    storage::IdentificationRecord x;
    try {
        x = storage::identification_from_json(p.dump());
    } catch (const storage::FormatError& e) {
        throw ReportError(e.what());
    }
    IdentifiedModel m;
    m.converged = x.converged;
    m.iterations = x.iterations;
    if (x.initial_rms_um) m.residual_rms_before_um = *x.initial_rms_um;
    m.residual_rms_after_um = x.residual_rms_um;
    for (const auto& e : x.estimates) {
        ModelParameter mp;
        mp.name = e.name;
        const auto [factor, unit] = display_unit(e.unit);
        mp.unit = unit;
        mp.value = e.estimate * factor;
        mp.uncertainty = e.std * factor;
        mp.observability = e.independence;
        if (!e.observable) mp.note = "not observable: held fixed";
        m.parameters.push_back(mp);
    }
    r.model = m;
}

/// Display name, unit and factor of an explaining variable of the discovery workflow.
struct VariableInfo {
    std::string label, unit;
    double factor = 1;
};
VariableInfo variable_info(const std::string& v) {
    if (v == "time") return {"session time", "s", 1};
    if (v == "bar_temperature") return {"bar temperature", "°C", 1};
    if (v == "X" || v == "Y" || v == "Z") return {v, "mm", 1};
    if (v == "A" || v == "B" || v == "C") return {v, "°", analysis::rad_to_deg(1.0)};
    if (v == "bar_direction") return {"bar direction", "", 1};
    return {v, "", 1};
}

/// The binned residual trend against `variable` among a run's trends.
const storage::DiscoveryTrend* trend_of(const std::vector<storage::DiscoveryTrend>& trends,
                                        const std::string& variable) {
    for (const auto& t : trends)
        if (t.variable == variable) return t.x.empty() || t.x.size() != t.before_um.size() ? nullptr : &t;
    return nullptr;
}

void add_discovery(Report& r, const json& p) {
    storage::DiscoveryRecord rec;
    try {
        rec = storage::discovery_from_json(p.dump());
    } catch (const storage::FormatError& e) {
        throw ReportError(e.what());
    }
    for (std::size_t step_index = 0; step_index < rec.steps.size(); ++step_index) {
        const storage::DiscoveryStepRecord& s = rec.steps[step_index];
        DiscoveryStep d;
        d.effect = s.effect;
        if (!s.iso.empty()) d.effect += " (" + s.iso + ")";
        if (s.per_reading) {  // per-reading residuals against the variable, before and after the step
            d.variable = s.variable;
            d.variable_unit = s.variable_unit;
            d.x = s.x;
            d.before_um = s.before_um;
            d.after_um = s.after_um;
        } else {  // `ballbar discover`: binned trends, the step's own or (older results) the whole run's
            const VariableInfo vi = variable_info(s.explained_by);
            d.variable = vi.label;
            d.variable_unit = vi.unit;
            if (step_index < rec.step_trends.size()) {
                const storage::DiscoveryTrend& t = rec.step_trends[step_index];
                if (t.x_unit) {  // a learned term: display units already
                    d.variable = t.variable;
                    d.variable_unit = *t.x_unit;
                    d.y_label = t.y_label;
                    d.y_unit = t.y_unit;
                }
                if (!t.x.empty() && t.before_um.size() == t.x.size() && t.after_um.size() == t.x.size()) {
                    d.x = t.x;
                    if (!t.x_unit)
                        for (double& xv : d.x) xv *= vi.factor;
                    d.before_um = t.before_um;
                    d.after_um = t.after_um;
                    d.binned = true;
                    d.own_step = true;
                }
            }
            const storage::DiscoveryTrend* before = trend_of(rec.residuals_initial, s.explained_by);
            const storage::DiscoveryTrend* after = trend_of(rec.residuals_final, s.explained_by);
            if (!d.binned && before && after && after->x.size() == before->x.size()) {
                d.x = before->x;
                for (double& x : d.x) x *= vi.factor;
                d.before_um = before->before_um;
                d.after_um = after->before_um;
                d.binned = true;
            }
        }
        if (s.rms_before_um) d.rms_before_um = *s.rms_before_um;
        if (s.rms_after_um) d.rms_after_um = *s.rms_after_um;
        d.accepted = s.accepted.value_or(!s.per_reading);  // the workflow lists the effects it added
        d.note = !s.note.empty() ? s.note : s.where;
        if (s.kind == "empirical") d.effect += " (learned)";
        if (d.note.empty() && s.kind != "empirical" && s.value) {
            const auto [factor, unit] = display_unit(s.unit);
            char buf[96];
            std::snprintf(buf, sizeof buf, "%.4g ± %.2g %s", *s.value * factor, s.value_std.value_or(0) * factor,
                          unit.c_str());
            d.note = buf;
        }
        r.discovery.push_back(d);
    }
    // The noise floor and the verdicts (`ballbar discover` since the search beyond the library).
    if (rec.noise_floor_um) {
        char buf[200];
        std::snprintf(buf, sizeof buf, "Noise floor %.3f µm (%s).", *rec.noise_floor_um,
                      rec.noise_source.value_or("").c_str());
        r.discovery_notes.emplace_back(buf);
    } else if (rec.noise_source) {
        r.discovery_notes.emplace_back("Noise floor unknown: whether the residual is noise cannot be decided.");
    }
    for (const auto* v : {&rec.verdict_before_search, &rec.verdict}) {
        if (!*v) continue;
        const bool final = v == &rec.verdict;
        const storage::DiscoveryVerdict& x = **v;
        char buf[240];
        if (x.ratio)
            std::snprintf(buf, sizeof buf,
                          "%s: residual RMS %.3f µm = %.2f× the floor: %s (χ² %.1f on %.0f dof, p = %.3g).",
                          final ? "Final" : "Before the search beyond the library", x.rms_um.value_or(0), *x.ratio,
                          x.result.c_str(), x.chi2.value_or(0), x.dof.value_or(0), x.p_value.value_or(1));
        else
            std::snprintf(buf, sizeof buf, "%s: residual RMS %.3f µm (%s).",
                          final ? "Final" : "Before the search beyond the library", x.rms_um.value_or(0),
                          x.result.c_str());
        r.discovery_notes.emplace_back(buf);
    }
    if (!rec.unlocated.empty())
        r.discovery_notes.push_back("Unexplained structure not located: " + rec.unlocated + ".");
}

void add_compensation(Report& r, const json& p) {
    storage::CompensationRecord c;
    try {
        c = storage::compensation_from_json(p.dump());
    } catch (const storage::FormatError& e) {
        throw ReportError(e.what());
    }
    r.compensation_metric = c.metric;
    for (const auto& a : c.axes) r.compensation.push_back({a.axis, "µm", a.before_um, a.after_um});
}

void add_procedure(Report& r, std::string_view kind, const json& p) {
    ProcedureEvent e;
    e.time_s = opt_num(kind, p, "time_s").value_or(0);
    e.timestamp = opt_str(kind, p, "at");
    const std::string event = opt_str(kind, p, "event");
    e.step = opt_str(kind, p, "to");
    e.detail = opt_str(kind, p, "detail");
    e.kind = event == "PointRejected" ? "repeat"
             : event == "DeviceLost"  ? "pause"
             : event == "DeviceBack"  ? "resume"
             : event == "Abort"       ? "abort"
             : event == "Fail"        ? "fail"
             : event == "Accepted"    ? "finish"
                                      : "step";
    if (e.detail.empty()) e.detail = event;
    r.procedure.push_back(e);
}

/// The stored plan: only its tolerances reach the report (the points come as points): the machine
/// file's, and each plan test's own.
void add_plan(Report& r, const json& p) {
    auto positive = [&](const json& t, const char* key) -> std::optional<double> {
        const json* v = find(t, key);
        if (!v) return std::nullopt;
        if (!v->is_number() || !(v->get<double>() > 0) || !std::isfinite(v->get<double>()))
            bad(acquisition::kPlanResultKind, key, "must be a number > 0");
        return v->get<double>();
    };
    const json* machine = find(p, "machine");
    if (const json* t = machine && machine->is_object() ? find(*machine, "tolerances") : nullptr; t && t->is_object()) {
        if ((r.location_tolerance_um = positive(*t, "location_um")))
            r.location_tolerance_source = "the machine file, stored with the session";
        if ((r.angle_tolerance_arcsec = positive(*t, "angle_arcsec")))
            r.angle_tolerance_source = "the machine file, stored with the session";
    }
    r.test_location_tolerance_um.clear(), r.test_angle_tolerance_arcsec.clear();
    const json* plan = find(p, "plan");
    const json* tests = plan && plan->is_object() ? find(*plan, "tests") : nullptr;
    if (!tests || !tests->is_array()) return;
    std::vector<int> own_location, own_angle;  // 1-based, as the screens number tests
    for (const json& test : *tests) {
        const json* t = test.is_object() ? find(test, "tolerances") : nullptr;
        const bool has = t && t->is_object();
        r.test_location_tolerance_um.push_back(has ? positive(*t, "location_um") : std::nullopt);
        r.test_angle_tolerance_arcsec.push_back(has ? positive(*t, "angle_arcsec") : std::nullopt);
        const int n = static_cast<int>(r.test_location_tolerance_um.size());
        if (r.test_location_tolerance_um.back()) own_location.push_back(n);
        if (r.test_angle_tolerance_arcsec.back()) own_angle.push_back(n);
    }
    // "the machine file, stored with the session; tests 2 and 3 their own, from the plan stored with the session".
    auto with_own = [](std::string& source, bool machine_too, const std::vector<int>& own) {
        std::string list = own.size() == 1 ? "test " : "tests ";
        for (std::size_t i = 0; i < own.size(); ++i)
            list += (i == 0 ? "" : i + 1 == own.size() ? " and " : ", ") + std::to_string(own[i]);
        source = (machine_too ? source + "; " : std::string()) + list + (own.size() == 1 ? " its" : " their") +
                 " own, from the plan stored with the session";
    };
    if (!own_location.empty()) with_own(r.location_tolerance_source, r.location_tolerance_um.has_value(), own_location);
    if (!own_angle.empty()) with_own(r.angle_tolerance_source, r.angle_tolerance_arcsec.has_value(), own_angle);
}

bool add_known_result(Report& report, std::string_view kind, const nlohmann::json& payload) {
    if (kind == acquisition::kPlanResultKind)
        add_plan(report, payload);
    else if (kind == "circular")
        add_circular(report, kind, payload);
    else if (kind == acquisition::kSsmResultKind)
        add_ssm(report, payload);
    else if (kind == acquisition::kOrientationResultKind)
        add_orientation(report, payload);
    else if (kind == storage::kIdentificationResultKind)
        add_identification(report, payload);
    else if (kind == "discovery")
        add_discovery(report, payload);
    else if (kind == "compensation")
        add_compensation(report, payload);
    else if (kind == "procedure" || kind == "acquisition.transition")
        add_procedure(report, kind, payload);
    else
        return false;
    return true;
}

}  // namespace

bool is_known_result_kind(std::string_view kind) {
    return kind == "ssm" || kind == "orientation" || kind == "identification" || kind == "discovery" ||
           kind == "compensation" || kind == "procedure" || kind == "acquisition.transition" || kind == "circular";
}

bool add_result(Report& report, std::string_view kind, const nlohmann::json& payload) {
    if (!payload.is_object()) {
        if (is_known_result_kind(kind)) throw ReportError("result \"" + std::string(kind) + "\": not a JSON object");
        return false;
    }
    try {
        return add_known_result(report, kind, payload);
    } catch (const acquisition::ResultFormatError& e) {
        throw ReportError(e.what());
    }
}

}  // namespace ballbar::report
