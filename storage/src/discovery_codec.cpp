// SPDX-License-Identifier: MIT
// The stored result of the discovery workflow (results table, kind "discovery"): its writer and its typed
// reader, one owner (docs/discovery.md). The reader also reads the shapes stored before docs/cli.md's
// vocabulary (estimate/stderr; rms in mm; per-reading residuals instead of binned trends).
#include "ballbar/storage/discovery_codec.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "ballbar/analysis/effects.hpp"
#include "stored_json.hpp"

namespace ballbar::storage {
namespace {

namespace ba = ballbar::analysis;
using ojson = nlohmann::ordered_json;

ojson text_or_null(const std::string& s) {
    return s.empty() ? ojson(nullptr) : ojson(s);
}

std::vector<std::string> param_names(const std::vector<ba::Param>& params) {
    std::vector<std::string> out;
    for (ba::Param p : params) out.emplace_back(ba::param_info(p).name);
    return out;
}

/// Degrees of freedom are counts (docs/cli.md): the analysis keeps them as doubles for its statistics.
ojson dof_json(double dof1, double dof2) {
    return ojson::array({std::llround(dof1), std::llround(dof2)});
}

/// The result in docs/cli.md's vocabulary (docs/discovery.md): a step's estimate is `value` with its
/// `unit` and `value_std`; the test's statistic is `statistic` under `criterion`.
ojson result_json(const ba::DiscoveryResult& r) {
    ojson steps = ojson::array();
    for (const ba::DiscoveryStep& st : r.steps) {
        const std::string iso(st.effect->iso);
        steps.push_back({{"effect", std::string(st.effect->id)},
                         {"iso", iso.empty() ? ojson(nullptr) : ojson(iso)},
                         {"kind", "library"},
                         {"unit", std::string(ba::to_string(st.effect->unit()))},
                         {"value", st.estimate},
                         {"value_std", st.std_error},
                         {"rms_before_um", st.rms_before_mm * 1e3},
                         {"rms_after_um", st.rms_after_mm * 1e3},
                         {"criterion", st.criterion},
                         {"statistic", st.value},
                         {"explained_by", std::string(ba::to_string(st.explained_by, r.type))},
                         {"accepted", !st.withdrawn},
                         {"withdrawn", st.withdrawn ? ojson("no longer passes given the learned terms (F-test, "
                                                            "Bonferroni over the model's library effects)")
                                                    : ojson(nullptr)}});
    }
    for (const ba::EmpiricalStep& st : r.learned) {
        ojson terms = ojson::array();
        for (const ba::LearnedTerm& t : st.terms)
            terms.push_back(
                {{"name", t.term.name()}, {"unit", t.term.unit()}, {"value", t.value}, {"value_std", t.std_error}});
        steps.push_back({{"effect", st.family},
                         {"kind", "empirical"},
                         {"where", st.description},
                         {"terms", terms},
                         {"rms_before_um", st.rms_before_mm * 1e3},
                         {"rms_after_um", st.rms_after_mm * 1e3},
                         {"criterion", "F"},
                         {"statistic", st.f},
                         {"dof", dof_json(st.dof1, st.dof2)},
                         {"p_value", st.p_value},
                         {"threshold_p", st.threshold_p},
                         {"explained_by", st.variable}});
    }
    auto verdict = [](const ba::NoiseVerdict& v) {
        // Without a known noise floor there is no test: its figures are null.
        const auto known = [&v](ojson x) { return v.floor_known ? x : ojson(nullptr); };
        return ojson{{"result", v.text},
                     {"rms_um", v.rms_mm * 1e3},
                     {"ratio", known(v.ratio)},
                     {"statistic", known("chi-square")},
                     {"chi2", known(v.chi2)},
                     {"dof", known(std::llround(v.dof))},
                     {"p_value", known(v.p_value)},
                     {"alpha", known(v.alpha)}};
    };
    return ojson{{"base_model", param_names(r.base_model)},
                 {"rms_initial_um", r.rms_initial_mm * 1e3},
                 {"steps", steps},
                 {"rms_final_um", r.rms_final_mm * 1e3},
                 {"confounded", r.confounded},
                 {"unidentifiable", r.unidentifiable},
                 {"noise_floor_um", r.noise_floor.known() ? ojson(r.noise_floor.sigma_mm * 1e3) : ojson(nullptr)},
                 {"noise_source", text_or_null(r.noise_floor.source)},
                 {"noise_detail", text_or_null(r.noise_floor.detail)},
                 {"verdict_before_search", verdict(r.verdict_library)},
                 {"verdict", verdict(r.verdict)},
                 {"unlocated", text_or_null(r.unlocated)}};
}

/// The learned terms as the stored model holds them ({"C_angular_h1_cos": value, ...}).
ojson empirical_json(std::span<const ba::LearnedTerm> terms) {
    ojson e = ojson::object();
    for (const ba::LearnedTerm& t : terms) e[t.term.name()] = t.value;
    return e;
}

ojson params_json(const std::vector<ba::Param>& model, const ba::ErrorParams& values) {
    ojson p = ojson::object();
    for (ba::Param q : model) p[std::string(ba::param_info(q).name)] = values[q];
    return p;
}

/// The display unit of a learned step's variable (detail::term_trend's bin centres).
std::string x_unit(const ba::EmpiricalStep& st) {
    if (st.family.find("_angular") != std::string::npos) return "°";
    if (st.family.find("_positioning") != std::string::npos) return "mm";
    if (st.family == "time") return "min";
    if (st.family == "bar_temperature" || st.family == "air_temperature") return "°C";
    return "";
}

/// What the stored result holds beyond the printed JSON: the criterion and the residual analysis.
ojson details_json(const ba::DiscoveryResult& r, const std::vector<std::string>& inputs) {
    auto trends = [&r](const ba::ResidualAnalysis& a) {
        ojson t = ojson::array();
        for (const auto& v : a.trends)
            t.push_back({{"variable", std::string(ba::to_string(v.variable, r.type))},
                         {"r2", v.r2},
                         {"bin_centre", v.bin_centre},
                         {"bin_mean_um", [&v] {
                              std::vector<double> um;
                              for (double m : v.bin_mean_mm) um.push_back(m * 1e3);
                              return um;
                          }()}});
        return t;
    };
    auto um = [](const std::vector<double>& mm) {
        std::vector<double> out;
        for (double m : mm) out.push_back(m * 1e3);
        return out;
    };
    ojson step_trends = ojson::array();  // each step's own before/after, against its variable
    for (const ba::DiscoveryStep& st : r.steps)
        step_trends.push_back({{"variable", std::string(ba::to_string(st.explained_by, r.type))},
                               {"bin_centre", st.trend_before.bin_centre},
                               {"before_um", um(st.trend_before.bin_mean_mm)},
                               {"after_um", um(st.trend_after.bin_mean_mm)}});
    for (const ba::EmpiricalStep& st : r.learned) {
        ojson families = ojson::array();
        for (const ba::FamilyScore& f : st.families)
            families.push_back({{"family", f.family},
                                {"variable", f.variable},
                                {"terms", f.terms},
                                {"f", f.f},
                                {"dof", dof_json(f.dof1, f.dof2)},
                                {"p_value", f.p_value},
                                {"passes", f.passes}});
        step_trends.push_back({{"variable", st.variable},
                               {"bin_centre", st.trend_before.bin_centre},
                               {"before_um", um(st.trend_before.bin_mean_mm)},
                               {"after_um", um(st.trend_after.bin_mean_mm)},
                               {"x_unit", x_unit(st)},
                               {"y_label", st.trend_label},
                               {"y_unit", st.trend_unit},
                               {"search", families}});
    }
    return {{"inputs", inputs},
            {"criterion", r.criterion_text},
            {"final_model", params_json(r.final_model, r.final_fit.model)},
            {"learned_terms", empirical_json(r.learned_terms)},
            {"residuals_initial", trends(r.initial_residuals)},
            {"residuals_final", trends(r.final_residuals)},
            {"step_trends", step_trends}};
}

}  // namespace

std::string discovery_to_json(const ba::DiscoveryResult& result) {
    return result_json(result).dump();
}

std::string discovery_to_json(const ba::DiscoveryResult& result, const DiscoveryStored& stored) {
    ojson payload = result_json(result);
    payload["details"] = details_json(result, stored.inputs);
    payload["model"] = {{"name", stored.model_name}, {"id", stored.model_id}, {"version", stored.model_version}};
    return payload.dump();
}

namespace {

using json = nlohmann::json;

using detail::find;
using detail::nums;
using detail::opt_num;
using detail::str;

std::vector<double> times(std::vector<double> v, double factor) {
    for (double& x : v) x *= factor;
    return v;
}

std::vector<DiscoveryTrend> residual_trends(const json* list) {
    std::vector<DiscoveryTrend> out;
    if (!list || !list->is_array()) return out;
    for (const auto& t : *list) {
        DiscoveryTrend d;
        d.variable = str(t, "variable");
        d.x = nums(t, "bin_centre");
        d.before_um = nums(t, "bin_mean_um");
        out.push_back(std::move(d));
    }
    return out;
}

std::optional<DiscoveryVerdict> verdict_of(const json& p, const char* key) {
    const json* v = find(p, key);
    if (!v || !v->is_object()) return std::nullopt;
    DiscoveryVerdict d;
    d.result = str(*v, "result");
    d.rms_um = opt_num(*v, "rms_um");
    d.ratio = opt_num(*v, "ratio");
    d.chi2 = opt_num(*v, "chi2");
    d.dof = opt_num(*v, "dof");
    d.p_value = opt_num(*v, "p_value");
    return d;
}

DiscoveryRecord read_discovery(const json& p) {
    DiscoveryRecord r;
    const json* steps = find(p, "steps");
    if (!steps || !steps->is_array()) detail::bad_key("steps", "must be an array");
    for (const auto& s : *steps) {
        DiscoveryStepRecord d;
        d.effect = str(s, "effect");
        d.iso = str(s, "iso");
        d.kind = str(s, "kind");
        d.unit = str(s, "unit");
        // docs/cli.md's vocabulary (value, value_std), or as results were stored before it (estimate, stderr).
        d.value = find(s, "estimate") ? opt_num(s, "estimate") : opt_num(s, "value");
        d.value_std = find(s, "estimate") ? opt_num(s, "stderr") : opt_num(s, "value_std");
        if (const auto v = opt_num(s, "rms_before_mm")) d.rms_before_um = *v * 1000;
        if (const auto v = opt_num(s, "rms_after_mm")) d.rms_after_um = *v * 1000;
        if (const auto v = opt_num(s, "rms_before_um")) d.rms_before_um = *v;
        if (const auto v = opt_num(s, "rms_after_um")) d.rms_after_um = *v;
        if (const json* a = find(s, "accepted"); a && a->is_boolean()) d.accepted = a->get<bool>();
        d.explained_by = str(s, "explained_by");
        d.where = str(s, "where");
        d.note = str(s, "note");
        if (find(s, "x")) {
            d.per_reading = true;
            d.variable = str(s, "variable");
            d.variable_unit = str(s, "variable_unit");
            d.x = nums(s, "x");
            d.before_um = times(nums(s, "before_mm"), 1000);
            d.after_um = times(nums(s, "after_mm"), 1000);
            if (d.before_um.size() != d.x.size() || d.after_um.size() != d.x.size())
                detail::bad_key("x", "must have as many values as before_mm and after_mm");
        }
        r.steps.push_back(std::move(d));
    }
    r.rms_initial_um = opt_num(p, "rms_initial_um");
    r.rms_final_um = opt_num(p, "rms_final_um");
    r.noise_floor_um = opt_num(p, "noise_floor_um");
    if (find(p, "noise_source")) r.noise_source = str(p, "noise_source");
    r.verdict_before_search = verdict_of(p, "verdict_before_search");
    r.verdict = verdict_of(p, "verdict");
    r.unlocated = str(p, "unlocated");
    if (const json* details = find(p, "details")) {
        if (const json* st = find(*details, "step_trends"); st && st->is_array()) {
            for (const auto& t : *st) {
                DiscoveryTrend d;
                d.variable = str(t, "variable");
                d.x = nums(t, "bin_centre");
                d.before_um = nums(t, "before_um");
                d.after_um = nums(t, "after_um");
                if (find(t, "x_unit")) d.x_unit = str(t, "x_unit");
                d.y_label = str(t, "y_label");
                d.y_unit = str(t, "y_unit");
                r.step_trends.push_back(std::move(d));
            }
        }
        r.residuals_initial = residual_trends(find(*details, "residuals_initial"));
        r.residuals_final = residual_trends(find(*details, "residuals_final"));
    }
    if (const json* m = find(p, "model"); m && m->is_object()) {
        r.model_name = str(*m, "name");
        if (const auto v = opt_num(*m, "version")) r.model_version = static_cast<int>(*v);
    }
    return r;
}

}  // namespace

DiscoveryRecord discovery_from_json(std::string_view text) {
    return detail::read_stored(text, "discovery", read_discovery);
}

}  // namespace ballbar::storage
