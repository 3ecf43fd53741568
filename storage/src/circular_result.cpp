// SPDX-License-Identifier: MIT
// The stored payload of a circular test's result ("ballbar circular/1").
#include "ballbar/storage/circular_result.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <vector>

#include "ballbar/analysis/rounding.hpp"
#include "stored_json.hpp"

namespace ballbar::storage {

namespace {
namespace circ = analysis::circular;
using ojson = nlohmann::ordered_json;
}  // namespace

std::string circular_result_json(const circ::CircularResult& r, const TraceFile& trace,
                                 std::optional<double> tolerance_um) {
    ojson j;
    j["test"] = ojson::parse(test_json(r.test));
    ojson runs = ojson::array();
    for (const auto& run : r.runs) {
        // The model curve at 0.001° and 0.1 nm: finer than the plot can show, and short text.
        ojson arc = ojson::array(), dev = ojson::array();
        for (std::size_t i = 0; i < run.model_arc_deg.size() && i < run.model_deviation_um.size(); ++i) {
            arc.push_back(analysis::decimal_round(run.model_arc_deg[i], 3));
            dev.push_back(analysis::decimal_round(run.model_deviation_um[i], 4));
        }
        runs.push_back({{"direction", circ::direction_name(run.direction)},
                        {"circularity_um", run.circularity_um},
                        {"radial_deviation_um", {{"max", run.radial_max_um}, {"min", run.radial_min_um}}},
                        {"feed_in_end_s", run.feed_in_end_s},
                        {"feed_in_lag_ms", run.servo_lag_s * 1e3},
                        {"data_start_s", run.data_start_s},
                        {"data_end_s", run.data_end_s},
                        {"samples", run.last_sample - run.first_sample},
                        {"model_curve", {{"arc_deg", arc}, {"deviation_um", dev}}}});
    }
    j["runs"] = runs;
    j["bidirectional_circularity_um"] = r.bidirectional_um ? ojson(*r.bidirectional_um) : ojson(nullptr);
    j["hysteresis_um"] = r.hysteresis_um ? ojson(*r.hysteresis_um) : ojson(nullptr);
    j["radial_deviation_um"] = {{"max", r.radial_max_um}, {"min", r.radial_min_um}};
    // docs/cli.md's vocabulary: the detected diagnostics one list, ranked first by their share of the
    // circular deviation; each with its unit, value and standard uncertainty.
    ojson diags = ojson::array(), missing = ojson::array();
    int rank = 0;
    for (const bool ranked : {true, false})
        for (const auto& d : r.diagnostics) {
            if (!d.detected || (d.contribution_um > 0.0) != ranked) continue;
            diags.push_back({{"key", d.key},
                             {"unit", circ::diagnostic_unit(d.diag)},
                             {"value", d.value},
                             {"value_std", d.std_uncertainty},
                             {"share_percent", ranked ? ojson(d.share_percent) : ojson(nullptr)},
                             {"rank", ranked ? ojson(++rank) : ojson(nullptr)}});
        }
    for (const auto& d : r.diagnostics)
        if (!d.detected) missing.push_back(d.key);
    j["diagnostics"] = diags;
    j["not_detected"] = missing;
    ojson groups = ojson::array();
    for (const auto& g : r.unseparable) {
        const bool combined = !g.combined_key.empty();
        groups.push_back({{"keys", g.keys},
                          {"reason", g.reason},
                          {"combined_key", combined ? ojson(g.combined_key) : ojson(nullptr)},
                          {"combined_value", combined ? ojson(g.combined_value) : ojson(nullptr)},
                          {"combined_value_std", combined ? ojson(g.combined_std) : ojson(nullptr)}});
    }
    j["unseparable"] = groups;
    j["residual_rms_um"] = r.residual_rms_um;
    j["mean_radius_um"] = r.mean_radius_um;
    j["mean_radius_um_std"] = r.mean_radius_std_um;
    ojson cond = {{"plane", circ::plane_name(r.test.plane)},
                  {"radius_mm", r.test.radius_mm},
                  {"feed_mm_min", r.test.feed_mm_min},
                  {"sample_rate_hz", r.sample_rate_hz},
                  {"samples_used", r.samples_used}};
    auto range = [](const std::vector<std::optional<double>>& v) -> ojson {
        double lo = 1e300, hi = -1e300;
        for (const auto& x : v)
            if (x) lo = std::min(lo, *x), hi = std::max(hi, *x);
        return lo <= hi ? ojson{{"min", lo}, {"max", hi}} : ojson(nullptr);
    };
    cond["bar_temp_C"] = range(trace.bar_temp_C);
    cond["air_temp_C"] = range(trace.air_temp_C);
    cond["instrument"] = trace.instrument_json.empty() ? ojson(nullptr) : ojson::parse(trace.instrument_json);
    j["conditions"] = cond;
    j["tolerance"] = nullptr;
    if (tolerance_um) {
        bool pass = true;
        for (const auto& run : r.runs) pass = pass && run.circularity_um <= *tolerance_um;
        j["tolerance"] = {{"circularity_um", *tolerance_um}, {"pass", pass}};
    }
    return j.dump();
}

}  // namespace ballbar::storage

namespace ballbar::storage {
namespace {

using json = nlohmann::json;

using detail::find;
using detail::num;
using detail::opt_num;
using detail::str;
using detail::strings;

/// The diagnostics as stored before the vocabulary: maps key → value (diagnostics, uncertainties,
/// shares_percent) and the ranked keys in order (ranking).
std::vector<StoredCircularDiagnostic> diagnostics_from_maps(const json& p) {
    std::vector<StoredCircularDiagnostic> out;
    const json* values = find(p, "diagnostics");
    if (!values || !values->is_object()) return out;
    const json* unc = find(p, "uncertainties");
    const json* shares = find(p, "shares_percent");
    const std::vector<std::string> ranking = strings(find(p, "ranking"));
    for (const auto& [key, v] : values->items()) {
        StoredCircularDiagnostic d;
        d.key = key;
        d.value = num(*values, key.c_str(), "diagnostics.");
        if (unc) d.value_std = opt_num(*unc, key.c_str(), "uncertainties.");
        if (shares) d.share_percent = opt_num(*shares, key.c_str(), "shares_percent.");
        if (const auto at = std::find(ranking.begin(), ranking.end(), key); at != ranking.end())
            d.rank = static_cast<int>(at - ranking.begin()) + 1;
        out.push_back(std::move(d));
    }
    return out;
}

CircularRecord read_circular(const json& p) {
    CircularRecord c;
    const json* test = find(p, "test");
    if (!test || !test->is_object()) detail::bad_key("test", "must be an object");
    c.plane = str(*test, "plane", "test.");
    c.radius_mm = num(*test, "radius_mm", "test.");
    c.feed_mm_min = num(*test, "feed_mm_min", "test.");
    c.feed_in_mm = opt_num(*test, "feed_in_mm", "test.").value_or(0);
    if (const json* ctr = find(*test, "centre_mm"); ctr && ctr->is_array() && ctr->size() == 3)
        for (std::size_t i = 0; i < 3; ++i)
            if ((*ctr)[i].is_number()) c.centre_mm[i] = (*ctr)[i].get<double>();
    const json* specs = find(*test, "runs");
    const json* runs = find(p, "runs");
    if (!runs || !runs->is_array() || runs->empty()) detail::bad_key("runs", "must be a non-empty array");
    for (std::size_t i = 0; i < runs->size(); ++i) {
        const json& j = (*runs)[i];
        const std::string where = "runs[" + std::to_string(i) + "].";
        StoredCircularRun r;
        r.direction = str(j, "direction", where);
        r.circularity_um = num(j, "circularity_um", where);
        if (const json* f = find(j, "radial_deviation_um")) {
            r.radial_max_um = num(*f, "max", where + "radial_deviation_um.");
            r.radial_min_um = num(*f, "min", where + "radial_deviation_um.");
        }
        r.feed_in_end_s = opt_num(j, "feed_in_end_s", where);
        r.feed_in_lag_ms = opt_num(j, "feed_in_lag_ms", where);
        r.data_start_s = opt_num(j, "data_start_s", where);
        r.data_end_s = opt_num(j, "data_end_s", where);
        r.samples = opt_num(j, "samples", where);
        if (const json* m = find(j, "model_curve")) {  // absent in results stored before it was drawn
            const std::string at = where + "model_curve.";
            auto numbers = [&](const char* key) {
                std::vector<double> out;
                const json* v = m->is_object() ? find(*m, key) : nullptr;
                if (!v || !v->is_array()) detail::bad_key(at + key, "must be an array of numbers");
                for (const auto& x : *v) {
                    if (!x.is_number()) detail::bad_key(at + key, "must be an array of numbers");
                    out.push_back(x.get<double>());
                }
                return out;
            };
            r.model_arc_deg = numbers("arc_deg");
            r.model_deviation_um = numbers("deviation_um");
            if (r.model_arc_deg.size() != r.model_deviation_um.size())
                detail::bad_key(at + "deviation_um", "must have as many numbers as arc_deg");
        }
        if (specs && specs->is_array() && i < specs->size()) {
            const json& s = (*specs)[i];
            r.start_deg = opt_num(s, "start_deg", "test." + where).value_or(0);
            r.overshoot_deg = opt_num(s, "overshoot_deg", "test." + where).value_or(0);
            r.data_arc_deg = opt_num(s, "data_arc_deg", "test." + where).value_or(360);
        }
        c.runs.push_back(std::move(r));
    }
    c.bidirectional_um = opt_num(p, "bidirectional_circularity_um");
    c.hysteresis_um = opt_num(p, "hysteresis_um");  // absent in results stored before it was computed
    if (const json* f = find(p, "radial_deviation_um")) {
        c.radial_max_um = num(*f, "max", "radial_deviation_um.");
        c.radial_min_um = num(*f, "min", "radial_deviation_um.");
    }
    if (const json* diags = find(p, "diagnostics"); diags && diags->is_array()) {
        for (std::size_t i = 0; i < diags->size(); ++i) {
            const json& d = (*diags)[i];
            const std::string where = "diagnostics[" + std::to_string(i) + "].";
            StoredCircularDiagnostic sd;
            sd.key = str(d, "key", where);
            sd.value = num(d, "value", where);
            sd.value_std = opt_num(d, "value_std", where);
            sd.share_percent = opt_num(d, "share_percent", where);
            if (const auto rk = opt_num(d, "rank", where)) sd.rank = static_cast<int>(*rk);
            c.diagnostics.push_back(std::move(sd));
        }
    } else {
        c.diagnostics = diagnostics_from_maps(p);
    }
    c.not_detected = strings(find(p, "not_detected"));
    if (const json* groups = find(p, "unseparable"); groups && groups->is_array()) {
        for (const auto& g : *groups) {
            StoredUnseparable u;
            u.keys = strings(find(g, "keys"));
            u.reason = str(g, "reason", "unseparable.");
            if (const json* comb = find(g, "combined")) {  // before the vocabulary
                u.combined_key = str(*comb, "as", "unseparable.combined.");
                u.combined_value = opt_num(*comb, "value", "unseparable.combined.");
                u.combined_value_std = opt_num(*comb, "std_uncertainty", "unseparable.combined.");
            } else if (find(g, "combined_key")) {
                u.combined_key = str(g, "combined_key", "unseparable.");
                u.combined_value = opt_num(g, "combined_value", "unseparable.");
                u.combined_value_std = opt_num(g, "combined_value_std", "unseparable.");
            }
            c.unseparable.push_back(std::move(u));
        }
    }
    c.residual_rms_um = opt_num(p, "residual_rms_um");
    if (const json* m = find(p, "mean_radius_um"); m && m->is_object()) {  // before the vocabulary
        c.mean_radius_um = opt_num(*m, "value", "mean_radius_um.");
        c.mean_radius_um_std = opt_num(*m, "std_uncertainty", "mean_radius_um.");
    } else {
        c.mean_radius_um = opt_num(p, "mean_radius_um");
        c.mean_radius_um_std = opt_num(p, "mean_radius_um_std");
    }
    if (const json* cond = find(p, "conditions")) {
        c.sample_rate_hz = opt_num(*cond, "sample_rate_hz", "conditions.");
        c.samples_used = opt_num(*cond, "samples_used", "conditions.");
        if (const json* r = find(*cond, "bar_temp_C"); r && r->is_object()) {
            c.bar_temp_min_C = opt_num(*r, "min", "conditions.bar_temp_C.");
            c.bar_temp_max_C = opt_num(*r, "max", "conditions.bar_temp_C.");
        }
        if (const json* r = find(*cond, "air_temp_C"); r && r->is_object()) {
            c.air_temp_min_C = opt_num(*r, "min", "conditions.air_temp_C.");
            c.air_temp_max_C = opt_num(*r, "max", "conditions.air_temp_C.");
        }
        if (const json* ins = find(*cond, "instrument"))
            c.instrument = ins->is_string() ? ins->get<std::string>() : ins->dump();
    }
    if (const json* tol = find(p, "tolerance")) c.tolerance_um = opt_num(*tol, "circularity_um", "tolerance.");
    return c;
}

}  // namespace

CircularRecord circular_result_from_json(std::string_view text) {
    return detail::read_stored(text, "circular", read_circular);
}

}  // namespace ballbar::storage
