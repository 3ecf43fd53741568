// SPDX-License-Identifier: MIT
#include "ballbar/workflow/trend.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "ballbar/acquisition/result_codec.hpp"
#include "ballbar/analysis/types.hpp"
#include "ballbar/storage/circular_result.hpp"
#include "ballbar/storage/identification_codec.hpp"

namespace ballbar::workflow {

namespace acq = ballbar::acquisition;

std::string machine_label(const analysis::MachineGeometry& m) {
    std::string s(analysis::to_string(m.type));
    if (!m.name.empty()) s += " " + m.name;
    return s;
}

std::string machine_label(const storage::SessionInfo& session) {
    return session.machine_asset.empty() ? machine_label(session.machine) : session.machine_asset;
}

namespace {

void circular_figures(const storage::CircularRecord& r, TrendPoint& p) {
    double g = 0;
    for (const auto& run : r.runs) g = std::max(g, run.circularity_um);
    if (!r.runs.empty()) {
        // The session's headline G is the largest of its planes; each plane has its own series.
        p.figures["G_um"] = std::max(p.figures.count("G_um") ? p.figures["G_um"] : 0.0, g);
        p.figures["G_" + r.plane + "_um"] = g;
    }
    if (r.bidirectional_um) p.figures["G_b_um"] = *r.bidirectional_um;
    if (r.hysteresis_um) p.figures["H_um"] = *r.hysteresis_um;
    for (const auto& d : r.diagnostics) {
        std::string key;
        if (d.key == "backlash_x_um" || d.key == "backlash_y_um" || d.key == "backlash_z_um") key = d.key;
        if (d.key == "squareness_um_per_m") {
            p.figures[d.key] = d.value;  // the web page's series, as before
            if (d.value_std) p.uncertainties[d.key] = *d.value_std;
            key = "squareness_" + r.plane + "_um_per_m";
        }
        if (key.empty()) continue;
        p.figures[key] = d.value;
        if (d.value_std) p.uncertainties[key] = *d.value_std;
    }
}

/// An identified parameter under a name with its unit, in the units an engineer reads: µm, arcsec, µm/m.
void identification_figures(const storage::IdentificationRecord& r, TrendPoint& p) {
    if (!r.converged) return;
    for (const auto& e : r.estimates) {
        if (!e.observable || e.name.find("socket") != std::string::npos) continue;  // the set-up, not the machine
        double scale = 1;
        std::string unit;
        if (e.unit == "mm") {
            scale = 1e3;
            unit = "um";
        } else if (e.unit == "rad") {
            scale = analysis::rad_to_arcsec(1.0);
            unit = "arcsec";
        } else if (e.unit == "mm/mm" || e.unit == "mm_per_mm") {
            scale = 1e6;
            unit = "um_per_m";
        } else {
            continue;  // a unit the trend does not plot (per kelvin, per hour: the thermal terms)
        }
        const std::string key = e.name + "_" + unit;
        p.figures[key] = e.estimate * scale;
        if (e.std > 0) p.uncertainties[key] = e.std * scale;
    }
}

struct AngleMeans {
    double sum[3] = {0, 0, 0};
    double var[3] = {0, 0, 0};  ///< sum of the variances, arcsec²
    int n[3] = {0, 0, 0};
    bool all_std[3] = {true, true, true};
};

}  // namespace

TrendPoint session_figures(const TrendSessionInput& s) {
    TrendPoint p;
    p.session = s.session;
    p.uuid = s.uuid;
    p.started_at = s.started_at;
    p.procedure = s.procedure;
    p.demo = s.demo;
    double dv_max = -1, dv_std = 0;
    AngleMeans angles;
    for (const auto& [kind, payload] : s.results) {
        try {
            if (kind == "circular") {
                circular_figures(storage::circular_result_from_json(payload), p);
            } else if (kind == acq::kSsmResultKind) {
                const acq::LocationResult l = acq::location_from_json(payload);
                const double norm = l.dV_mm.norm();
                if (1e3 * norm > dv_max) {
                    dv_max = 1e3 * norm;
                    // |ΔV|'s uncertainty to first order, from the components' (the stored result keeps
                    // their standard uncertainties, not their covariance).
                    const analysis::Vec3 u = norm > 0 ? analysis::Vec3(l.dV_mm / norm) : analysis::Vec3::Zero();
                    dv_std = 1e3 * std::sqrt(u.cwiseProduct(l.ssm.std_mm).squaredNorm());
                }
            } else if (kind == acq::kOrientationResultKind) {
                const acq::TestResult t = acq::test_from_json(payload);
                if (!t.orientation.exact) continue;
                const auto m = acq::measured_angles(s.type, t.kind);
                const double v[3] = {t.orientation.exact->d_alpha_rad, t.orientation.exact->d_beta_rad,
                                     t.orientation.exact->d_gamma_rad};
                const double sd[3] = {t.std_rad ? t.std_rad->d_alpha_rad : 0.0, t.std_rad ? t.std_rad->d_beta_rad : 0.0,
                                      t.std_rad ? t.std_rad->d_gamma_rad : 0.0};
                const bool on[3] = {m.alpha, m.beta, m.gamma};
                for (int k = 0; k < 3; ++k)
                    if (on[k]) {
                        angles.sum[k] += analysis::rad_to_arcsec(v[k]);
                        const double a = analysis::rad_to_arcsec(sd[k]);
                        angles.var[k] += a * a;
                        angles.all_std[k] = angles.all_std[k] && a > 0;
                        ++angles.n[k];
                    }
            } else if (kind == storage::kIdentificationResultKind) {
                identification_figures(storage::identification_from_json(payload), p);
            }
        } catch (const std::exception&) {
            continue;  // an unreadable result: its session's page says why
        }
    }
    if (dv_max >= 0) {
        p.figures["dV_max_um"] = dv_max;
        if (dv_std > 0) p.uncertainties["dV_max_um"] = dv_std;
    }
    const char* names[3] = {"d_alpha_arcsec", "d_beta_arcsec", "d_gamma_arcsec"};
    for (int k = 0; k < 3; ++k)
        if (angles.n[k] > 0) {
            p.figures[names[k]] = angles.sum[k] / angles.n[k];
            if (angles.all_std[k]) p.uncertainties[names[k]] = std::sqrt(angles.var[k]) / angles.n[k];
        }
    return p;
}

TrendPoint session_figures(storage::Store& store, const storage::SessionInfo& s) {
    TrendSessionInput in;
    in.session = s.id;
    in.uuid = s.uuid;
    in.started_at = s.started_at;
    in.procedure = s.procedure;
    in.demo = s.source == storage::SessionSource::emulator;
    in.type = s.machine.type;
    for (auto& r : store.results(s.id)) in.results.emplace_back(std::move(r.kind), std::move(r.payload_json));
    return session_figures(in);
}

std::string headline(const TrendPoint& p) {
    char text[64];
    if (const auto g = p.figures.find("G_um"); g != p.figures.end()) {
        std::snprintf(text, sizeof text, "G %.1f µm", g->second);
        return text;
    }
    if (const auto dv = p.figures.find("dV_max_um"); dv != p.figures.end()) {
        std::snprintf(text, sizeof text, "|ΔV| max %.1f µm", dv->second);
        return text;
    }
    return {};
}

std::vector<TrendPoint> machine_trend(storage::Store& store, const std::string& machine) {
    std::vector<TrendPoint> out;
    for (const auto& s : store.sessions()) {
        if (s.state != storage::SessionState::completed || machine_label(s) != machine) continue;
        TrendPoint p = session_figures(store, s);
        if (!p.figures.empty()) out.push_back(std::move(p));
    }
    std::stable_sort(out.begin(), out.end(),
                     [](const TrendPoint& a, const TrendPoint& b) { return a.started_at < b.started_at; });
    return out;
}

std::string trend_json(const std::string& machine, const std::vector<TrendPoint>& points) {
    nlohmann::ordered_json out{{"machine", machine}, {"points", nlohmann::ordered_json::array()}};
    for (const auto& p : points)
        out["points"].push_back({{"session", p.session},
                                 {"started_at", p.started_at},
                                 {"procedure", p.procedure},
                                 {"demo", p.demo},
                                 {"figures", p.figures}});
    return out.dump();
}

}  // namespace ballbar::workflow
