// SPDX-License-Identifier: MIT
// The circular test's content: stored result → CircularTest; the polar plot's points.
#include "circular.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "ballbar/report/decimate.hpp"

namespace ballbar::report {

namespace {

using nlohmann::json;
constexpr double kDeg = std::numbers::pi / 180.0;

[[noreturn]] void bad(const std::string& key, const std::string& what) {
    throw ReportError("result \"circular\": \"" + key + "\" " + what);
}

const json* find(const json& j, const char* key) {
    if (!j.is_object()) return nullptr;
    const auto it = j.find(key);
    return it == j.end() || it->is_null() ? nullptr : &*it;
}
std::optional<double> opt_num(const json& j, const char* key, const std::string& where = {}) {
    const json* v = find(j, key);
    if (!v) return std::nullopt;
    if (!v->is_number()) bad(where + key, "must be a number");
    return v->get<double>();
}
double num(const json& j, const char* key, const std::string& where = {}) {
    const auto v = opt_num(j, key, where);
    if (!v) bad(where + key, "is missing");
    return *v;
}
std::string str(const json& j, const char* key, const std::string& where = {}) {
    const json* v = find(j, key);
    if (!v) return {};
    if (!v->is_string()) bad(where + key, "must be a string");
    return v->get<std::string>();
}
const json& object(const json& j, const char* key) {
    const json* v = find(j, key);
    if (!v || !v->is_object()) bad(key, "must be an object");
    return *v;
}

bool ends_with(std::string_view s, std::string_view suffix) {
    return s.size() >= suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}

/// "backlash_x_um" → name "backlash X", unit "µm" (the format's keys, docs/formats/trace.md).
void name_and_unit(CircularDiagnostic& d) {
    std::string k = d.key;
    static const std::pair<const char*, const char*> units[] = {{"_um_per_m", "µm/m"}, {"_ppm", "ppm"}, {"_ms", "ms"},
                                                                {"_um", "µm"},         {"_mm", "mm"},   {"_hz", "Hz"}};
    for (const auto& [suffix, unit] : units) {
        if (ends_with(k, suffix)) {
            d.unit = unit;
            k.erase(k.size() - std::string_view(suffix).size());
            break;
        }
    }
    // A trailing axis letter ("_x") is written as the axis's capital.
    if (k.size() > 2 && k[k.size() - 2] == '_' && (k.back() == 'x' || k.back() == 'y' || k.back() == 'z')) {
        const char axis = static_cast<char>(k.back() - 'a' + 'A');
        k.erase(k.size() - 2);
        k += ' ';
        k += axis;
    }
    std::replace(k.begin(), k.end(), '_', ' ');
    if (d.key == "vibration_hz") k = "vibration frequency";
    d.name = k;
}

Range range_of(const json* r) {
    Range out;
    if (!r || !r->is_object()) return out;
    out.min = opt_num(*r, "min", "conditions.");
    out.max = opt_num(*r, "max", "conditions.");
    if (out.min && out.max) out.mean = 0.5 * (*out.min + *out.max);  // the middle of the range
    return out;
}

}  // namespace

bool CircularTest::pass() const {
    if (!tolerance_um) return false;
    for (const auto& r : runs)
        if (!(r.circularity_um <= *tolerance_um)) return false;
    return !runs.empty();
}

void add_circular(Report& report, std::string_view, const json& p) {
    CircularTest c;
    const json& test = object(p, "test");
    c.plane = str(test, "plane", "test.");
    c.radius_mm = num(test, "radius_mm", "test.");
    c.feed_mm_min = num(test, "feed_mm_min", "test.");
    c.feed_in_mm = opt_num(test, "feed_in_mm", "test.").value_or(0);
    if (const json* ctr = find(test, "centre_mm"); ctr && ctr->is_array() && ctr->size() == 3)
        for (int i = 0; i < 3; ++i)
            if ((*ctr)[static_cast<std::size_t>(i)].is_number())
                c.centre_mm[i] = (*ctr)[static_cast<std::size_t>(i)].get<double>();
    const json* specs = find(test, "runs");
    const json* runs = find(p, "runs");
    if (!runs || !runs->is_array() || runs->empty()) bad("runs", "must be a non-empty array");
    for (std::size_t i = 0; i < runs->size(); ++i) {
        const json& j = (*runs)[i];
        const std::string where = "runs[" + std::to_string(i) + "].";
        CircularRun r;
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
        if (specs && specs->is_array() && i < specs->size()) {
            const json& s = (*specs)[i];
            r.start_deg = opt_num(s, "start_deg", "test." + where).value_or(0);
            r.overshoot_deg = opt_num(s, "overshoot_deg", "test." + where).value_or(0);
            r.data_arc_deg = opt_num(s, "data_arc_deg", "test." + where).value_or(360);
        }
        c.runs.push_back(std::move(r));
    }
    c.bidirectional_um = opt_num(p, "bidirectional_circularity_um");
    if (const json* f = find(p, "radial_deviation_um")) {
        c.radial_max_um = num(*f, "max", "radial_deviation_um.");
        c.radial_min_um = num(*f, "min", "radial_deviation_um.");
    }
    // Diagnostics: the ranked ones in their order, each followed by its pitch or frequency, then the rest.
    // Stored as one list ({key, unit, value, value_std, share_percent, rank}, docs/cli.md), or, before
    // the vocabulary, as maps (diagnostics, uncertainties, shares_percent) and a ranking: the list is
    // read into the maps' form.
    json from_list_diags = json::object(), from_list_unc = json::object(), from_list_shares = json::object();
    std::vector<std::string> order;
    const json* diags = find(p, "diagnostics");
    const json* unc = find(p, "uncertainties");
    const json* shares = find(p, "shares_percent");
    if (diags && diags->is_array()) {
        std::vector<std::pair<int, std::string>> ranked;
        for (std::size_t i = 0; i < diags->size(); ++i) {
            const json& d = (*diags)[i];
            const std::string where = "diagnostics[" + std::to_string(i) + "].";
            const std::string key = str(d, "key", where);
            from_list_diags[key] = num(d, "value", where);
            if (const auto u = opt_num(d, "value_std", where)) from_list_unc[key] = *u;
            if (const auto sh = opt_num(d, "share_percent", where)) from_list_shares[key] = *sh;
            if (const auto rk = opt_num(d, "rank", where)) ranked.emplace_back(static_cast<int>(*rk), key);
        }
        std::sort(ranked.begin(), ranked.end());
        for (const auto& [rk, key] : ranked) order.push_back(key);
        diags = &from_list_diags;
        unc = &from_list_unc;
        shares = &from_list_shares;
    } else if (const json* ranking = find(p, "ranking"); ranking && ranking->is_array()) {
        for (const auto& k : *ranking)
            if (k.is_string()) order.push_back(k.get<std::string>());
    }
    auto companion = [](const std::string& key) -> std::string {
        if (key.rfind("cyclic_error_", 0) == 0) return "cyclic_pitch_" + key.substr(13, 1) + "_mm";
        if (key == "vibration_um") return "vibration_hz";
        return {};
    };
    std::vector<std::string> keys;
    for (const auto& k : order) {
        keys.push_back(k);
        if (const std::string m = companion(k); !m.empty()) keys.push_back(m);
    }
    if (diags && diags->is_object())
        for (const auto& [k, v] : diags->items())
            if (std::find(keys.begin(), keys.end(), k) == keys.end()) keys.push_back(k);
    int rank = 0;
    for (const auto& k : keys) {
        if (!diags || !diags->is_object() || !diags->contains(k)) continue;
        CircularDiagnostic d;
        d.key = k;
        d.value = num(*diags, k.c_str(), "diagnostics.");
        if (unc) d.uncertainty = opt_num(*unc, k.c_str(), "uncertainties.");
        if (shares) d.share_percent = opt_num(*shares, k.c_str(), "shares_percent.");
        if (std::find(order.begin(), order.end(), k) != order.end()) d.rank = ++rank;
        name_and_unit(d);
        c.diagnostics.push_back(std::move(d));
    }
    if (const json* nd = find(p, "not_detected"); nd && nd->is_array())
        for (const auto& k : *nd)
            if (k.is_string()) c.not_detected.push_back(k.get<std::string>());
    if (const json* groups = find(p, "unseparable"); groups && groups->is_array()) {
        for (const auto& g : *groups) {
            CircularUnseparable u;
            if (const json* ks = find(g, "keys"); ks && ks->is_array())
                for (const auto& k : *ks)
                    if (k.is_string()) u.keys.push_back(k.get<std::string>());
            u.reason = str(g, "reason", "unseparable.");
            if (const json* comb = find(g, "combined")) {  // before the vocabulary
                u.combined_key = str(*comb, "as", "unseparable.combined.");
                u.combined_value = opt_num(*comb, "value", "unseparable.combined.");
                u.combined_uncertainty = opt_num(*comb, "std_uncertainty", "unseparable.combined.");
            } else if (find(g, "combined_key")) {
                u.combined_key = str(g, "combined_key", "unseparable.");
                u.combined_value = opt_num(g, "combined_value", "unseparable.");
                u.combined_uncertainty = opt_num(g, "combined_value_std", "unseparable.");
            }
            c.unseparable.push_back(std::move(u));
        }
    }
    c.residual_rms_um = opt_num(p, "residual_rms_um");
    if (const json* m = find(p, "mean_radius_um"); m && m->is_object()) {  // before the vocabulary
        c.mean_radius_um = opt_num(*m, "value", "mean_radius_um.");
        c.mean_radius_uncertainty_um = opt_num(*m, "std_uncertainty", "mean_radius_um.");
    } else {
        c.mean_radius_um = opt_num(p, "mean_radius_um");
        c.mean_radius_uncertainty_um = opt_num(p, "mean_radius_um_std");
    }
    if (const json* cond = find(p, "conditions")) {
        c.sample_rate_hz = opt_num(*cond, "sample_rate_hz", "conditions.");
        c.samples_used = opt_num(*cond, "samples_used", "conditions.");
        c.bar_temp_C = range_of(find(*cond, "bar_temp_C"));
        c.air_temp_C = range_of(find(*cond, "air_temp_C"));
        if (const json* ins = find(*cond, "instrument"))
            c.instrument = ins->is_string() ? ins->get<std::string>() : ins->dump();
    }
    if (const json* tol = find(p, "tolerance")) {
        c.tolerance_um = opt_num(*tol, "circularity_um", "tolerance.");
        if (c.tolerance_um) c.tolerance_source = "stored with the result";
    }
    report.circular = std::move(c);
}

void circular_polar(CircularTest& c, std::span<const CircularSample> samples, std::size_t columns) {
    if (!(c.radius_mm > 0) || !(c.feed_mm_min > 0)) return;
    const double omega = c.feed_mm_min / 60.0 / c.radius_mm;  // rad/s
    // The axes follow their command through the servo lag: the mean of the feed-ins' lags.
    double lag_s = 0;
    int n_lag = 0;
    for (const auto& r : c.runs)
        if (r.feed_in_lag_ms) lag_s += *r.feed_in_lag_ms * 1e-3, ++n_lag;
    const double phase = n_lag > 0 ? std::atan(omega * lag_s / n_lag) : 0.0;
    struct Pt {
        std::size_t run;
        double arc_deg, theta, y_um;
    };
    std::vector<Pt> pts;
    for (std::size_t k = 0; k < c.runs.size(); ++k) {
        const CircularRun& r = c.runs[k];
        if (!r.feed_in_end_s || !r.data_start_s || !r.data_end_s) continue;
        const double dir = r.direction == "cw" ? -1.0 : 1.0;
        const auto first = std::lower_bound(samples.begin(), samples.end(), *r.data_start_s,
                                            [](const CircularSample& s, double t) { return s.time_s < t; });
        for (auto it = first; it != samples.end() && it->time_s <= *r.data_end_s; ++it) {
            const double travelled = omega * (it->time_s - *r.feed_in_end_s);
            pts.push_back({k, (travelled - r.overshoot_deg * kDeg) / kDeg,
                           r.start_deg * kDeg + dir * (travelled - phase), (it->measured_mm - c.radius_mm) * 1e3});
        }
    }
    if (pts.size() < 3) return;
    // One least-squares circle for every run (G(b)'s centre): 1, cos θ, sin θ.
    Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (const auto& p : pts) {
        const Eigen::Vector3d row(1.0, std::cos(p.theta), std::sin(p.theta));
        a += row * row.transpose();
        b += row * p.y_um;
    }
    const Eigen::Vector3d fit = a.ldlt().solve(b);
    for (std::size_t k = 0; k < c.runs.size(); ++k) {
        CircularRun& r = c.runs[k];
        MinMaxDecimator dec(0.0, std::max(r.data_arc_deg, 1.0), std::max<std::size_t>(columns, 1));
        std::vector<double> theta_of;
        for (const auto& p : pts) {
            if (p.run != k) continue;
            dec.add(p.arc_deg, p.y_um - (fit[0] + fit[1] * std::cos(p.theta) + fit[2] * std::sin(p.theta)));
        }
        XYSeries kept = dec.take();
        const double dir = r.direction == "cw" ? -1.0 : 1.0;
        r.angle_deg.clear();
        for (double arc : kept.x) {
            double deg = r.start_deg + dir * (r.overshoot_deg + arc - phase / kDeg);
            deg = std::fmod(deg, 360.0);
            if (deg < 0) deg += 360.0;
            r.angle_deg.push_back(deg);
        }
        r.deviation_um = std::move(kept.y);
    }
    c.plot_deviation_um = circular_plot_range(c);
}

void set_circular_tolerance(Report& report, double tolerance_um) {
    if (!report.circular) return;
    report.circular->tolerance_um = tolerance_um;
    report.circular->tolerance_source = "given";
    report.circular->plot_deviation_um = circular_plot_range(*report.circular);
}

double circular_plot_range(const CircularTest& c) {
    double largest = c.tolerance_um ? 0.5 * *c.tolerance_um : 0.0;
    for (const auto& r : c.runs)
        for (double v : r.deviation_um) largest = std::max(largest, std::abs(v));
    if (!(largest > 0) || !std::isfinite(largest)) return 1.0;
    const double mag = std::pow(10.0, std::floor(std::log10(largest)));
    for (double f : {1.0, 2.0, 2.5, 5.0, 10.0})
        if (f * mag >= largest * (1 - 1e-12)) return f * mag;
    return 10 * mag;
}

}  // namespace ballbar::report
