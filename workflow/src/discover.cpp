// SPDX-License-Identifier: MIT
#include "ballbar/workflow/discover.hpp"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <span>

#include "ballbar/analysis/effects.hpp"
#include "ballbar/storage/model_codec.hpp"
#include "ballbar/workflow/error.hpp"

namespace ballbar::workflow {
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

/// A version of the model as it is stored (ballbar-model/1): the parameters `model` names, their values.
std::string stored_model(const ba::MachineGeometry& machine, const std::vector<ba::Param>& model,
                         const ba::ErrorParams& values, std::span<const ba::LearnedTerm> learned = {},
                         std::string added = {}) {
    storage::ErrorModel m;
    m.machine = machine;
    for (ba::Param q : model) m.params.push_back({q, values[q], std::nullopt});
    m.empirical.assign(learned.begin(), learned.end());
    m.added = std::move(added);
    return storage::model_to_json(m);
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

/// Stores the result with every input session and the extended model, one version per step; the last.
storage::ModelRecord store_result(storage::Store& store, const ReadingInputs& in, const ba::DiscoveryResult& r,
                                  const std::string& name, const ba::MachineGeometry& machine) {
    storage::ModelRecord rec = store.save_model(name, stored_model(machine, r.base_model, r.base_fit), in.sessions,
                                                std::nullopt, "discovery: base model");
    std::vector<ba::Param> model = r.base_model;
    for (const ba::DiscoveryStep& st : r.steps) {
        model.push_back(st.effect->param);
        char note[200];
        std::snprintf(note, sizeof note, "discovery: added %s%s%s, RMS %.3f -> %.3f um",
                      std::string(st.effect->id).c_str(), st.effect->iso.empty() ? "" : " ",
                      std::string(st.effect->iso).c_str(), st.rms_before_mm * 1e3, st.rms_after_mm * 1e3);
        rec = store.save_model(name, stored_model(machine, model, st.model_after, {}, std::string(st.effect->id)),
                               in.sessions, rec.id, note);
    }
    std::vector<ba::LearnedTerm> learned;
    for (const ba::EmpiricalStep& st : r.learned) {
        learned.insert(learned.end(), st.terms.begin(), st.terms.end());
        char note[300];
        std::snprintf(note, sizeof note, "discovery: learned %s (%s), RMS %.3f -> %.3f um", st.family.c_str(),
                      st.description.c_str(), st.rms_before_mm * 1e3, st.rms_after_mm * 1e3);
        rec = store.save_model(name, stored_model(machine, r.final_model, r.final_fit.model, learned, st.family),
                               in.sessions, rec.id, note);
    }
    ojson payload = result_json(r);
    payload["details"] = details_json(r, in.names);
    payload["model"] = {{"name", name}, {"id", rec.id}, {"version", rec.version}};
    for (std::int64_t s : in.sessions)
        store.add_result(s, "discovery", payload.dump(), rec.id,
                         std::string("ballbar ") + BALLBAR_VERSION + " discovery/1");
    return rec;
}

}  // namespace

std::string discovery_json(const ba::DiscoveryResult& result) {
    return result_json(result).dump();
}

DiscoverResult discover(ReadingInputs in, const DiscoverOptions& o, const StoreOpener& for_writing) {
    DiscoverResult out;
    out.input_names = in.names;
    try {
        out.readings = ba::merge_readings(std::move(in.sets));  // moved: the readings are held once
    } catch (const ba::AnalysisError& e) {
        throw Error(ErrorCategory::bad_input, std::string("cannot combine the inputs: ") + e.what());
    }
    ba::DiscoveryOptions opt;
    if (o.noise_um) {
        if (!(*o.noise_um > 0) || !std::isfinite(*o.noise_um))
            throw Error(ErrorCategory::bad_input, "--noise-um: must be a positive number of micrometres");
        opt.noise_mm = *o.noise_um * 1e-3;
    }
    if (!o.model.empty()) {
        try {
            opt.base_model = ba::parse_model(o.model, out.readings.machine.type);
        } catch (const ba::AnalysisError& e) {
            throw Error(ErrorCategory::bad_input, std::string("--model: ") + e.what());
        }
    }
    try {
        out.result = ba::discover(out.readings, opt);
    } catch (const ba::AnalysisError& e) {
        throw Error(ErrorCategory::failed, std::string("discovery failed: ") + e.what());
    }
    if (for_writing && !in.sessions.empty()) {
        const ba::MachineGeometry& machine = out.readings.machine;
        const std::string name =
            !o.save_model.empty() ? o.save_model : (machine.name.empty() ? "machine" : machine.name) + "-discovered";
        out.stored = store_result(for_writing(), in, out.result, name, machine);
    }
    return out;
}

}  // namespace ballbar::workflow
