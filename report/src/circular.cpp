// SPDX-License-Identifier: MIT
// The circular test's content: stored result → CircularTest; the polar plot's points.
#include "circular.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "ballbar/report/advice.hpp"
#include "ballbar/report/decimate.hpp"
#include "ballbar/storage/circular_result.hpp"
#include "ballbar/storage/machine_json.hpp"

namespace ballbar::report {

namespace {

using nlohmann::json;
constexpr double kDeg = std::numbers::pi / 180.0;

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

Range range_of(std::optional<double> min, std::optional<double> max) {
    Range out;
    out.min = min;
    out.max = max;
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
    storage::CircularRecord rec;
    try {
        rec = storage::circular_result_from_json(p.dump());
    } catch (const storage::FormatError& e) {
        throw ReportError(e.what());
    }
    CircularTest c;
    c.plane = rec.plane;
    c.radius_mm = rec.radius_mm;
    c.feed_mm_min = rec.feed_mm_min;
    c.feed_in_mm = rec.feed_in_mm;
    c.centre_mm = Vec3(rec.centre_mm[0], rec.centre_mm[1], rec.centre_mm[2]);
    for (const auto& sr : rec.runs) {
        CircularRun r;
        r.direction = sr.direction;
        r.start_deg = sr.start_deg;
        r.overshoot_deg = sr.overshoot_deg;
        r.data_arc_deg = sr.data_arc_deg;
        r.circularity_um = sr.circularity_um;
        r.radial_max_um = sr.radial_max_um.value_or(0);
        r.radial_min_um = sr.radial_min_um.value_or(0);
        r.feed_in_end_s = sr.feed_in_end_s;
        r.feed_in_lag_ms = sr.feed_in_lag_ms;
        r.data_start_s = sr.data_start_s;
        r.data_end_s = sr.data_end_s;
        r.samples = sr.samples;
        r.model_arc_deg = sr.model_arc_deg;
        r.model_deviation_um = sr.model_deviation_um;
        c.runs.push_back(std::move(r));
    }
    c.bidirectional_um = rec.bidirectional_um;
    c.hysteresis_um = rec.hysteresis_um;
    c.radial_max_um = rec.radial_max_um.value_or(0);
    c.radial_min_um = rec.radial_min_um.value_or(0);
    // Diagnostics: the ranked ones in their order, each followed by its pitch or frequency, then the rest.
    std::vector<const storage::StoredCircularDiagnostic*> ranked;
    for (const auto& d : rec.diagnostics)
        if (d.rank) ranked.push_back(&d);
    std::stable_sort(ranked.begin(), ranked.end(), [](const auto* a, const auto* b) { return *a->rank < *b->rank; });
    auto companion = [](const std::string& key) -> std::string {
        if (key.rfind("cyclic_error_", 0) == 0) return "cyclic_pitch_" + key.substr(13, 1) + "_mm";
        if (key == "vibration_um") return "vibration_hz";
        return {};
    };
    std::vector<std::string> keys;
    for (const auto* d : ranked) {
        keys.push_back(d->key);
        if (const std::string m = companion(d->key); !m.empty()) keys.push_back(m);
    }
    for (const auto& d : rec.diagnostics)
        if (std::find(keys.begin(), keys.end(), d.key) == keys.end()) keys.push_back(d.key);
    int rank = 0;
    for (const auto& k : keys) {
        const auto it =
            std::find_if(rec.diagnostics.begin(), rec.diagnostics.end(), [&k](const auto& d) { return d.key == k; });
        if (it == rec.diagnostics.end()) continue;
        CircularDiagnostic d;
        d.key = k;
        d.value = it->value;
        d.uncertainty = it->value_std;
        d.share_percent = it->share_percent;
        if (it->rank) d.rank = ++rank;
        name_and_unit(d);
        if (d.rank > 0) d.action = diagnostic_action(d.key, d.value, d.uncertainty.value_or(0), rec.plane);
        c.diagnostics.push_back(std::move(d));
    }
    c.not_detected = rec.not_detected;
    for (const auto& g : rec.unseparable)
        c.unseparable.push_back({g.keys, g.reason, g.combined_key, g.combined_value, g.combined_value_std});
    c.residual_rms_um = rec.residual_rms_um;
    c.mean_radius_um = rec.mean_radius_um;
    c.mean_radius_uncertainty_um = rec.mean_radius_um_std;
    c.sample_rate_hz = rec.sample_rate_hz;
    c.samples_used = rec.samples_used;
    c.bar_temp_C = range_of(rec.bar_temp_min_C, rec.bar_temp_max_C);
    c.air_temp_C = range_of(rec.air_temp_min_C, rec.air_temp_max_C);
    c.instrument = rec.instrument;
    c.tolerance_um = rec.tolerance_um;
    if (c.tolerance_um) c.tolerance_source = "stored with the result";
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
        auto angle = [&](double arc) {
            double deg = r.start_deg + dir * (r.overshoot_deg + arc - phase / kDeg);
            deg = std::fmod(deg, 360.0);
            return deg < 0 ? deg + 360.0 : deg;
        };
        r.angle_deg.clear();
        for (double arc : kept.x) r.angle_deg.push_back(angle(arc));
        r.deviation_um = std::move(kept.y);
        r.model_angle_deg.clear();
        for (double arc : r.model_arc_deg) r.model_angle_deg.push_back(angle(arc));
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
        for (const auto* series : {&r.deviation_um, &r.model_deviation_um})
            for (double v : *series) largest = std::max(largest, std::abs(v));
    if (!(largest > 0) || !std::isfinite(largest)) return 1.0;
    const double mag = std::pow(10.0, std::floor(std::log10(largest)));
    for (double f : {1.0, 2.0, 2.5, 5.0, 10.0})
        if (f * mag >= largest * (1 - 1e-12)) return f * mag;
    return 10 * mag;
}

}  // namespace ballbar::report
