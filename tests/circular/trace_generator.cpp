// SPDX-License-Identifier: MIT
// Independent circular-test generator (see trace_generator.hpp). Written from the format alone.
#include "trace_generator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>

namespace ballbar::testgen {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct Segment {
    double t0 = 0.0, t1 = 0.0;
    std::function<std::array<double, 2>(double)> at;  // plane position relative to the centre
    bool data = false;
    int run = -1;
};

/// Kasa's algebraic circle fit: the centre.
std::array<double, 2> kasa_centre(const std::vector<std::array<double, 2>>& pts) {
    double mx = 0, my = 0;
    for (const auto& p : pts) mx += p[0], my += p[1];
    mx /= static_cast<double>(pts.size()), my /= static_cast<double>(pts.size());
    double sxx = 0, sxy = 0, syy = 0, sx = 0, sy = 0, n = 0, sxz = 0, syz = 0, sz = 0;
    for (const auto& p : pts) {
        const double x = p[0] - mx, y = p[1] - my, z = -(x * x + y * y);
        sxx += x * x, sxy += x * y, syy += y * y, sx += x, sy += y, n += 1, sxz += x * z, syz += y * z, sz += z;
    }
    const double a[3][3] = {{sxx, sxy, sx}, {sxy, syy, sy}, {sx, sy, n}};
    const double b[3] = {sxz, syz, sz};
    auto det3 = [](const double m[3][3]) {
        return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
               m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    };
    const double d = det3(a);
    double sol[3];
    for (int c = 0; c < 3; ++c) {
        double m[3][3];
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) m[i][j] = j == c ? b[i] : a[i][j];
        sol[c] = det3(m) / d;
    }
    return {-sol[0] / 2.0 + mx, -sol[1] / 2.0 + my};
}

/// Max − min distance to the Kasa centre (µm).
double circle_g(const std::vector<std::array<double, 2>>& pts) {
    const auto [cx, cy] = kasa_centre(pts);
    double lo = 1e300, hi = -1e300;
    for (const auto& p : pts) {
        const double r = std::hypot(p[0] - cx, p[1] - cy);
        lo = std::min(lo, r), hi = std::max(hi, r);
    }
    return (hi - lo) * 1e3;
}

std::function<std::array<double, 2>(double)> standing(double radius, double angle) {
    return [=](double) { return std::array<double, 2>{radius * std::cos(angle), radius * std::sin(angle)}; };
}

}  // namespace

const char* plane_text(int plane) {
    return plane == 0 ? "XY" : plane == 1 ? "YZ" : "ZX";
}

GenTrace generate(const GenSpec& spec, const GenEffects& fx, std::mt19937_64& rng) {
    const int ip = spec.plane == 0 ? 0 : spec.plane == 1 ? 1 : 2;
    const int iq = spec.plane == 0 ? 1 : spec.plane == 1 ? 2 : 0;
    const int io = 3 - ip - iq;
    const double R = spec.radius_mm, v = spec.feed_mm_min / 60.0, w = v / R, fi = spec.feed_in_mm;
    const double cp = spec.centre_mm[static_cast<std::size_t>(ip)], cq = spec.centre_mm[static_cast<std::size_t>(iq)];
    std::uniform_real_distribution<double> stand(0.3, 1.2);
    std::normal_distribution<double> noise(0.0, spec.noise_um * 1e-3);

    // The part program as timed segments of the commanded position.
    std::vector<Segment> segs;
    double t = 0.0;
    for (std::size_t k = 0; k < spec.runs.size(); ++k) {
        const GenRun& run = spec.runs[k];
        const double s = run.start_deg * kPi / 180.0, sg = run.ccw ? 1.0 : -1.0, tf = fi / v;
        const double ts = stand(rng);
        segs.push_back({t, t + ts, standing(R + fi, s)});
        t += ts;
        segs.push_back({t, t + tf, [=, t0 = t](double u) {
                            const double r = R + fi - v * (u - t0);
                            return std::array<double, 2>{r * std::cos(s), r * std::sin(s)};
                        }});
        t += tf;
        const double o = run.overshoot_deg * kPi / 180.0, d = run.data_arc_deg * kPi / 180.0;
        auto arc = [=, t_arc = t](double u) {
            const double a = s + sg * w * (u - t_arc);
            return std::array<double, 2>{R * std::cos(a), R * std::sin(a)};
        };
        segs.push_back({t, t + o / w, arc});
        t += o / w;
        segs.push_back({t, t + d / w, arc, true, static_cast<int>(k)});
        t += d / w;
        segs.push_back({t, t + o / w, arc});
        t += o / w;
        const double e = s + sg * (2.0 * o + d);
        segs.push_back({t, t + tf, [=, t0 = t](double u) {
                            const double r = R + v * (u - t0);
                            return std::array<double, 2>{r * std::cos(e), r * std::sin(e)};
                        }});
        t += tf;
        if (k + 1 == spec.runs.size()) {
            segs.push_back({t, t + 0.5, standing(R + fi, e)});
            t += 0.5;
        }
    }
    const double t_end = t;
    std::size_t seg = 0;
    auto command = [&](double u) {
        while (seg + 1 < segs.size() && u >= segs[seg].t1) ++seg;
        return segs[seg].at(std::min(u, segs[seg].t1));
    };

    GenTrace out;
    const double dt = 1.0 / spec.sample_hz;
    const int sub = 8;
    const double h = dt / sub;
    const double keep[2] = {std::exp(-h / (fx.lag_ms[0] * 1e-3)), std::exp(-h / (fx.lag_ms[1] * 1e-3))};
    std::array<double, 2> act = command(0.0);
    double sign[2] = {-1.0, -1.0}, rev_t[2] = {-1e9, -1e9}, rev_sign[2] = {0, 0};
    const double kstr[2] = {fx.straightness_um[0] * 1e-3 / (R * R), fx.straightness_um[1] * 1e-3 / (R * R)};
    const double sock_p = fx.socket_offset_um[static_cast<std::size_t>(ip)] * 1e-3;
    const double sock_q = fx.socket_offset_um[static_cast<std::size_t>(iq)] * 1e-3;
    const double sock_o = fx.socket_offset_um[static_cast<std::size_t>(io)] * 1e-3;
    std::vector<std::vector<std::array<double, 2>>> run_pts(spec.runs.size());
    std::vector<std::array<double, 2>> all_pts;
    double fmax = -1e300, fmin = 1e300;
    std::size_t ds = 0;
    for (long n = 0;; ++n) {
        const double tn = static_cast<double>(n) * dt;
        if (tn > t_end) break;
        if (n > 0) {
            for (int k = 0; k < sub; ++k) {
                const double tm = tn - dt + (k + 0.5) * h;
                const auto c = command(tm);
                for (std::size_t a = 0; a < 2; ++a) {
                    const double before = act[a];
                    act[a] = c[a] + (before - c[a]) * keep[a];
                    const double dv = act[a] - before;
                    if (std::abs(dv) > 1e-12) {
                        const double sgn = dv > 0 ? 1.0 : -1.0;
                        if (sgn != sign[a]) rev_t[a] = tm, rev_sign[a] = sign[a];
                        sign[a] = sgn;
                    }
                }
            }
        }
        const double P = cp + act[0], Q = cq + act[1];
        double ep = -sign[0] * fx.backlash_um[0] * 0.5e-3, eq = -sign[1] * fx.backlash_um[1] * 0.5e-3;
        ep += rev_sign[0] * fx.spike_um[0] * 1e-3 * std::exp(-(tn - rev_t[0]) / 0.015);
        eq += rev_sign[1] * fx.spike_um[1] * 1e-3 * std::exp(-(tn - rev_t[1]) / 0.015);
        ep += fx.scale_ppm[0] * 1e-6 * P + fx.squareness_um_per_m * 1e-6 * Q;
        eq += fx.scale_ppm[1] * 1e-6 * Q;
        ep += fx.cyclic_um[0] * 1e-3 * std::sin(2.0 * kPi * P / fx.pitch_mm[0] + fx.cyclic_phase[0]);
        eq += fx.cyclic_um[1] * 1e-3 * std::sin(2.0 * kPi * Q / fx.pitch_mm[1] + fx.cyclic_phase[1]);
        eq += kstr[0] * (P - cp) * (P - cp);
        ep += kstr[1] * (Q - cq) * (Q - cq);
        const double dx = P + ep - (cp + sock_p), dy = Q + eq - (cq + sock_q);
        const double len0 = std::sqrt(dx * dx + dy * dy + sock_o * sock_o);
        const double len = len0 +
                           fx.vibration_um * 1e-3 * std::sin(2.0 * kPi * fx.vibration_hz * tn + fx.vibration_phase) +
                           noise(rng);
        out.time_s.push_back(tn);
        out.measured_mm.push_back(len);
        while (ds + 1 < segs.size() && tn > segs[ds].t1) ++ds;
        if (segs[ds].data && tn >= segs[ds].t0 && tn <= segs[ds].t1) {
            const double planar = std::sqrt(std::max(len * len - sock_o * sock_o, 0.0));
            const double ang = std::atan2(dy, dx);
            const std::array<double, 2> pt{planar * std::cos(ang), planar * std::sin(ang)};
            run_pts[static_cast<std::size_t>(segs[ds].run)].push_back(pt);
            all_pts.push_back(pt);
            fmax = std::max(fmax, (len - R) * 1e3), fmin = std::min(fmin, (len - R) * 1e3);
        }
    }
    for (const auto& pts : run_pts) out.g_um.push_back(circle_g(pts));
    out.gb_um = circle_g(all_pts);
    // H: the two directions' distances to the common centre, compared degree by degree (each degree's
    // mean), as ISO 230-4 compares the two paths.
    std::size_t ccw = spec.runs.size(), cw = spec.runs.size();
    for (std::size_t k = 0; k < spec.runs.size(); ++k) {
        if (spec.runs[k].ccw && ccw == spec.runs.size()) ccw = k;
        if (!spec.runs[k].ccw && cw == spec.runs.size()) cw = k;
    }
    if (ccw < spec.runs.size() && cw < spec.runs.size()) {
        const auto c = kasa_centre(all_pts);
        auto sectors = [&](const std::vector<std::array<double, 2>>& pts) {
            std::vector<double> sum(360, 0.0), n(360, 0.0);
            for (const auto& p : pts) {
                double deg = std::atan2(p[1] - c[1], p[0] - c[0]) * 180.0 / kPi;
                if (deg < 0) deg += 360.0;
                const auto k = std::min<std::size_t>(359, static_cast<std::size_t>(deg));
                sum[k] += std::hypot(p[0] - c[0], p[1] - c[1]);
                n[k] += 1;
            }
            for (std::size_t k = 0; k < 360; ++k) sum[k] = n[k] > 0 ? sum[k] / n[k] : std::nan("");
            return sum;
        };
        const auto a = sectors(run_pts[ccw]), b = sectors(run_pts[cw]);
        out.h_um = 0;
        for (std::size_t k = 0; k < 360; ++k)
            if (!std::isnan(a[k]) && !std::isnan(b[k])) out.h_um = std::max(out.h_um, std::abs(a[k] - b[k]) * 1e3);
    }
    out.f_max_um = fmax, out.f_min_um = fmin;
    return out;
}

std::string to_file(const GenSpec& spec, const GenTrace& trace) {
    std::ostringstream os;
    os.precision(10);
    os << "# ballbar-trace/1\n# test: {\"kind\": \"circular\", \"plane\": \"" << plane_text(spec.plane)
       << "\", \"radius_mm\": " << spec.radius_mm << ", \"centre_mm\": [" << spec.centre_mm[0] << ", "
       << spec.centre_mm[1] << ", " << spec.centre_mm[2] << "], \"feed_mm_min\": " << spec.feed_mm_min
       << ", \"feed_in_mm\": " << spec.feed_in_mm << ", \"runs\": [";
    for (std::size_t k = 0; k < spec.runs.size(); ++k) {
        const GenRun& r = spec.runs[k];
        os << (k ? ", " : "") << "{\"direction\": \"" << (r.ccw ? "ccw" : "cw") << "\", \"start_deg\": " << r.start_deg
           << ", \"overshoot_deg\": " << r.overshoot_deg << ", \"data_arc_deg\": " << r.data_arc_deg << "}";
    }
    os << "]}\n# instrument: {\"model\": \"independent generator\"}\ntime_s,measured_mm\n";
    char line[64];
    for (std::size_t i = 0; i < trace.time_s.size(); ++i) {
        std::snprintf(line, sizeof line, "%.6f,%.7f\n", trace.time_s[i], trace.measured_mm[i]);
        os << line;
    }
    return os.str();
}

GenCase random_case(std::mt19937_64& rng, double p_effect) {
    auto uni = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
    auto coin = [&](double p) { return std::bernoulli_distribution(p)(rng); };
    GenCase c;
    GenSpec& s = c.spec;
    s.plane = std::uniform_int_distribution<int>(0, 2)(rng);
    s.radius_mm = uni(50.0, 150.0);
    for (auto& x : s.centre_mm) x = uni(-300.0, 300.0);
    s.feed_mm_min = uni(500.0, 2000.0);
    s.feed_in_mm = uni(1.0, 2.0);
    s.sample_hz = uni(300.0, 1000.0);
    s.noise_um = uni(0.1, 0.25);
    if (coin(0.5)) {
        const double o = uni(20.0, 90.0), s0 = uni(0.0, 360.0);
        s.runs = {{true, s0, o, 360.0}, {false, s0 + 2.0 * o + 360.0, o, 360.0}};
    } else {
        const double o = uni(15.0, 30.0);
        s.runs = {{true, -o, o, 180.0}, {false, 180.0 + o, o, 180.0}};
    }
    GenEffects& f = c.fx;
    auto amp = [&] { return uni(0.5, 5.0) * (coin(0.5) ? 1.0 : -1.0); };  // radial µm
    const double v = s.feed_mm_min / 60.0, R = s.radius_mm;
    for (auto& p : c.present) p = coin(p_effect);
    if (c.present[0]) f.backlash_um[0] = 2.0 * std::abs(amp()) * (coin(0.8) ? 1.0 : -1.0);
    if (c.present[1]) f.backlash_um[1] = 2.0 * std::abs(amp()) * (coin(0.8) ? 1.0 : -1.0);
    if (c.present[2]) f.spike_um[0] = uni(1.0, 6.0);
    if (c.present[3]) f.spike_um[1] = uni(1.0, 6.0);
    if (c.present[4]) f.squareness_um_per_m = amp() * 2000.0 / R;
    const double mean_scale = uni(-20.0, 20.0);
    f.scale_ppm = {mean_scale, mean_scale};
    if (c.present[5]) {
        const double mis = amp() * 2000.0 / R;
        f.scale_ppm = {mean_scale + 0.5 * mis, mean_scale - 0.5 * mis};
    }
    const double lag = uni(2.0, 30.0);
    f.lag_ms = {lag, lag};
    if (c.present[6]) {
        const double mis = amp() * 2.0 / v;
        f.lag_ms = {lag + 0.5 * mis, lag - 0.5 * mis};
    }
    const double max_pitch = std::min(20.0, R / 5.0);
    if (c.present[7])
        f.cyclic_um[0] = uni(0.5, 3.0), f.pitch_mm[0] = uni(2.5, max_pitch), f.cyclic_phase[0] = uni(0, 6.28);
    if (c.present[8])
        f.cyclic_um[1] = uni(0.5, 3.0), f.pitch_mm[1] = uni(2.5, max_pitch), f.cyclic_phase[1] = uni(0, 6.28);
    if (c.present[9]) f.straightness_um[0] = amp() / 0.3849;
    if (c.present[10]) f.straightness_um[1] = amp() / 0.3849;
    if (c.present[11]) {
        f.vibration_um = uni(0.5, 3.0);
        f.vibration_hz = uni(5.0, std::min(100.0, 0.4 * s.sample_hz));
        f.vibration_phase = uni(0.0, 6.28);
    }
    for (auto& o : f.socket_offset_um) o = uni(-30.0, 30.0);
    return c;
}

}  // namespace ballbar::testgen
