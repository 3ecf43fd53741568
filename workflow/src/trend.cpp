// SPDX-License-Identifier: MIT
#include "ballbar/workflow/trend.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "ballbar/acquisition/result_codec.hpp"
#include "ballbar/analysis/types.hpp"
#include "ballbar/storage/circular_result.hpp"

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
    if (!r.runs.empty()) p.figures["G_um"] = g;
    if (r.bidirectional_um) p.figures["G_b_um"] = *r.bidirectional_um;
    if (r.hysteresis_um) p.figures["H_um"] = *r.hysteresis_um;
    for (const auto& d : r.diagnostics)
        if (d.key == "backlash_x_um" || d.key == "backlash_y_um" || d.key == "backlash_z_um" ||
            d.key == "squareness_um_per_m")
            p.figures[d.key] = d.value;
}

struct AngleMeans {
    double sum[3] = {0, 0, 0};
    int n[3] = {0, 0, 0};
};

}  // namespace

TrendPoint session_figures(storage::Store& store, const storage::SessionInfo& s) {
    TrendPoint p;
    p.session = s.id;
    p.started_at = s.started_at;
    p.procedure = s.procedure;
    p.demo = s.source == storage::SessionSource::emulator;
    double dv_max = -1;
    AngleMeans angles;
    for (const auto& r : store.results(s.id)) {
        try {
            if (r.kind == "circular") {
                circular_figures(storage::circular_result_from_json(r.payload_json), p);
            } else if (r.kind == acq::kSsmResultKind) {
                dv_max = std::max(dv_max, 1e3 * acq::location_from_json(r.payload_json).dV_mm.norm());
            } else if (r.kind == acq::kOrientationResultKind) {
                const acq::TestResult t = acq::test_from_json(r.payload_json);
                if (!t.orientation.exact) continue;
                const auto m = acq::measured_angles(s.machine.type, t.kind);
                const double v[3] = {t.orientation.exact->d_alpha_rad, t.orientation.exact->d_beta_rad,
                                     t.orientation.exact->d_gamma_rad};
                const bool on[3] = {m.alpha, m.beta, m.gamma};
                for (int k = 0; k < 3; ++k)
                    if (on[k]) {
                        angles.sum[k] += analysis::rad_to_arcsec(v[k]);
                        ++angles.n[k];
                    }
            }
        } catch (const std::exception&) {
            continue;  // an unreadable result: its session's page says why
        }
    }
    if (dv_max >= 0) p.figures["dV_max_um"] = dv_max;
    const char* names[3] = {"d_alpha_arcsec", "d_beta_arcsec", "d_gamma_arcsec"};
    for (int k = 0; k < 3; ++k)
        if (angles.n[k] > 0) p.figures[names[k]] = angles.sum[k] / angles.n[k];
    return p;
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
