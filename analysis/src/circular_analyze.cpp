// SPDX-License-Identifier: MIT
// The circular test, end to end: the runs' data arcs from their feed-ins, the ISO 230-4 figures
// (G per run, G(b), F) and the diagnosis (circular_fit.cpp).
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "ballbar/analysis/types.hpp"
#include "circular_fit.hpp"

namespace ballbar::analysis::circular {
namespace {

constexpr double kDeg = kPi / 180.0;

std::string run_name(std::size_t i, const RunSpec& r) {
    return "run " + std::to_string(i + 1) + " (" + direction_name(r.direction) + ")";
}

/// A data point at the axes' angle: its radial deviation and the cosine and sine of the angle.
struct AnglePoint {
    double y_um, c, s;
};

/// The least-squares circle of the points [begin, end) (at least 3): mean radial deviation and the
/// centre's offset, as the coefficients of 1, cos θ and sin θ.
/// The normal equations' sums are plain doubles (the 3×3 is symmetric: six of them), not an Eigen outer
/// product per point, which a sanitizer build makes a dozen function calls.
Eigen::Vector3d least_squares_circle(const AnglePoint* begin, const AnglePoint* end) {
    double n = 0, sc = 0, ss = 0, scc = 0, scs = 0, sss = 0, sy = 0, syc = 0, sys = 0;
    for (const AnglePoint* p = begin; p != end; ++p) {
        n += 1.0, sc += p->c, ss += p->s, scc += p->c * p->c, scs += p->c * p->s, sss += p->s * p->s;
        sy += p->y_um, syc += p->c * p->y_um, sys += p->s * p->y_um;
    }
    Eigen::Matrix3d a;
    a << n, sc, ss, sc, scc, scs, ss, scs, sss;
    return a.ldlt().solve(Eigen::Vector3d(sy, syc, sys));
}

/// Max − min radial deviation of the points [begin, end) about the circle `c` (least_squares_circle's).
double spread_about(const AnglePoint* begin, const AnglePoint* end, const Eigen::Vector3d& c) {
    double lo = 0.0, hi = 0.0;
    bool first = true;
    for (const AnglePoint* p = begin; p != end; ++p) {
        const double e = p->y_um - (c[0] + c[1] * p->c + c[2] * p->s);
        lo = first ? e : std::min(lo, e), hi = first ? e : std::max(hi, e);
        first = false;
    }
    return hi - lo;
}

/// Each run's model curve (RunResult::model_*): the fit's explained part at its points, less one
/// least-squares circle of it over every run, min and max per kModelCurveStep_deg of the data arc.
void model_curves(const detail::FitInput& in, const detail::FitOutput& fit, double cos_lag, double sin_lag,
                  CircularResult& result) {
    const std::size_t n = in.points.size();
    if (fit.fitted_um.size() != n || n < 3) return;
    std::vector<AnglePoint> pts(n);
    for (std::size_t i = 0; i < n; ++i) {
        const detail::FitPoint& p = in.points[i];
        pts[i] = {fit.fitted_um[i], p.cos_theta * cos_lag + p.dir * p.sin_theta * sin_lag,
                  p.sin_theta * cos_lag - p.dir * p.cos_theta * sin_lag};
    }
    const Eigen::Vector3d c = least_squares_circle(pts.data(), pts.data() + n);
    // One pass over the points: each one's deviation about that circle, and per run and column the
    // indices of the lowest and highest point.
    constexpr std::size_t kNone = static_cast<std::size_t>(-1);
    std::vector<double> dev(n);
    std::vector<std::vector<std::size_t>> lo(result.runs.size()), hi(result.runs.size());
    for (std::size_t k = 0; k < result.runs.size(); ++k) {
        const auto columns =
            static_cast<std::size_t>(std::ceil(result.test.runs[k].data_arc_deg / kModelCurveStep_deg));
        lo[k].assign(columns, kNone), hi[k].assign(columns, kNone);
    }
    auto arc_deg = [&](std::size_t i) {
        return in.points[i].travelled / kDeg -
               result.test.runs[static_cast<std::size_t>(in.points[i].run)].overshoot_deg;
    };
    for (std::size_t i = 0; i < n; ++i) {
        const AnglePoint& p = pts[i];
        dev[i] = p.y_um - (c[0] + c[1] * p.c + c[2] * p.s);
        const auto k = static_cast<std::size_t>(in.points[i].run);
        auto& l = lo[k];
        auto& h = hi[k];
        const auto col = static_cast<std::size_t>(
            std::clamp(std::floor(arc_deg(i) / kModelCurveStep_deg), 0.0, static_cast<double>(l.size() - 1)));
        if (l[col] == kNone || dev[i] < dev[l[col]]) l[col] = i;
        if (h[col] == kNone || dev[i] > dev[h[col]]) h[col] = i;
    }
    for (std::size_t k = 0; k < result.runs.size(); ++k) {
        RunResult& run = result.runs[k];
        run.model_arc_deg.clear(), run.model_deviation_um.clear();
        auto add = [&](std::size_t i) {
            run.model_arc_deg.push_back(arc_deg(i));
            run.model_deviation_um.push_back(dev[i]);
        };
        for (std::size_t col = 0; col < lo[k].size(); ++col) {
            if (lo[k][col] == kNone) continue;
            add(std::min(lo[k][col], hi[k][col]));
            if (lo[k][col] != hi[k][col]) add(std::max(lo[k][col], hi[k][col]));
        }
    }
}

/// Max − min radial deviation about the least-squares centre of the points [begin, end).
double circular_deviation(const AnglePoint* begin, const AnglePoint* end) {
    return end - begin < 3 ? 0.0 : spread_about(begin, end, least_squares_circle(begin, end));
}

/// ISO 230-4's circular hysteresis H: the largest radial difference between the clockwise and the
/// counter-clockwise path, both about the least-squares centre of the two together (G(b)'s). The paths
/// are compared in 1° sectors of the angle (each sector's mean deviation, a hundred samples or so at
/// the usual feeds and rates, so the noise of single samples does not pass for hysteresis), over the
/// sectors both runs cover.
double circular_hysteresis(const AnglePoint* a_begin, const AnglePoint* a_end, const AnglePoint* b_begin,
                           const AnglePoint* b_end, const Eigen::Vector3d& centre) {
    constexpr int kSectors = 360;
    std::array<double, kSectors> sum_a{}, sum_b{};
    std::array<int, kSectors> n_a{}, n_b{};
    auto bin = [&](const AnglePoint* begin, const AnglePoint* end, std::array<double, kSectors>& sum,
                   std::array<int, kSectors>& n) {
        for (const AnglePoint* p = begin; p != end; ++p) {
            double deg = std::atan2(p->s, p->c) / kDeg;
            if (deg < 0) deg += 360.0;
            const auto k = std::min(kSectors - 1, static_cast<int>(deg));
            sum[static_cast<std::size_t>(k)] += p->y_um - (centre[0] + centre[1] * p->c + centre[2] * p->s);
            ++n[static_cast<std::size_t>(k)];
        }
    };
    bin(a_begin, a_end, sum_a, n_a);
    bin(b_begin, b_end, sum_b, n_b);
    double h = 0.0;
    for (std::size_t k = 0; k < kSectors; ++k)
        if (n_a[k] > 0 && n_b[k] > 0) h = std::max(h, std::abs(sum_a[k] / n_a[k] - sum_b[k] / n_b[k]));
    return h;
}

/// Throws when the samples from `from_s` (the feed-in's start) to `to_s` (the data arc's end) have a
/// step longer than `max_hole_s`: a stretch of the circle without data, or a jump of the clock that
/// would put every later sample at a wrong angle. The message names the run, the times and the angles.
void check_holes(std::size_t k, const RunSpec& spec, const std::vector<TraceSample>& samples, double from_s,
                 double to_s, double command_end_s, double omega, int dir, double max_hole_s) {
    auto at = std::lower_bound(samples.begin(), samples.end(), from_s,
                               [](const TraceSample& s, double t) { return s.time_s < t; });
    if (at != samples.begin()) --at;  // the step into the stretch counts too
    for (auto p = at; p + 1 != samples.end() && p->time_s < to_s; ++p) {
        const double gap_s = (p + 1)->time_s - p->time_s;
        if (gap_s <= max_hole_s) continue;
        auto angle_deg = [&](double t) {
            return spec.start_deg + dir * std::max(0.0, omega * (t - command_end_s)) / kDeg;
        };
        char text[320];
        std::snprintf(text, sizeof text,
                      ": no samples for %.3f s, from t = %.3f s to %.3f s (the commanded angle %.1f° to %.1f°): "
                      "a hole or a jump of the clock longer than %.3f s leaves angles unmeasured or misplaced; "
                      "no figures or verdict from this trace: measure the run again",
                      gap_s, p->time_s, (p + 1)->time_s, angle_deg(p->time_s), angle_deg((p + 1)->time_s), max_hole_s);
        throw CircularError(run_name(k, spec) + text);
    }
}

}  // namespace

const DiagnosticResult* CircularResult::find(Diag diag) const {
    for (const auto& d : diagnostics)
        if (d.diag == diag) return &d;
    return nullptr;
}

CircularResult analyze_circular(const TestSpec& test, const std::vector<TraceSample>& samples,
                                const AnalysisOptions& options) {
    if (const std::string bad = test.validate(); !bad.empty()) throw CircularError("test: " + bad);
    if (samples.size() < 10) throw CircularError("the trace has too few samples");
    for (std::size_t i = 1; i < samples.size(); ++i)
        if (!(samples[i].time_s > samples[i - 1].time_s))
            throw CircularError("time_s is not strictly increasing at sample " + std::to_string(i + 1));

    // The trace's sample period (the median step) sets what counts as a hole.
    double max_hole_s = 0.0;
    {
        std::vector<double> dt(samples.size() - 1);
        for (std::size_t i = 1; i < samples.size(); ++i) dt[i - 1] = samples[i].time_s - samples[i - 1].time_s;
        std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2), dt.end());
        max_hole_s = std::max(options.max_hole_s, 3.0 * dt[dt.size() / 2]);
    }

    CircularResult result;
    result.test = test;
    const double speed = test.feed_mm_min / 60.0;
    const double omega = speed / test.radius_mm;
    detail::FitInput in;
    in.test = test;
    in.omega_rad_s = omega;
    in.points.reserve(samples.size());  // an upper bound: one vector, never regrown (100k samples: 5 MB)
    std::size_t from = 0;
    bool ccw = false, cw = false;
    std::vector<double> steps;
    steps.reserve(samples.size());
    for (std::size_t k = 0; k < test.runs.size(); ++k) {
        const RunSpec& spec = test.runs[k];
        const auto feed = find_feed_in(test, samples, from);
        if (!feed)
            throw CircularError(run_name(k, spec) + ": no feed-in found after t = " +
                                std::to_string(samples[std::min(from, samples.size() - 1)].time_s) + " s (a fall of " +
                                std::to_string(test.feed_in_mm) + " mm at the test feed)");
        RunResult run;
        run.direction = spec.direction;
        run.feed_in_end_s = feed->command_end_s;
        run.servo_lag_s = feed->lag_s;
        run.data_start_s = feed->command_end_s + spec.overshoot_deg * kDeg / omega;
        run.data_end_s = run.data_start_s + spec.data_arc_deg * kDeg / omega;
        const double run_end_s = run.data_end_s + spec.overshoot_deg * kDeg / omega;
        if (samples.back().time_s < run.data_end_s)
            throw CircularError(run_name(k, spec) + ": the trace ends at " + std::to_string(samples.back().time_s) +
                                " s, before the data arc does (" + std::to_string(run.data_end_s) + " s)");
        const int dir = spec.direction == Direction::Ccw ? 1 : -1;
        (dir > 0 ? ccw : cw) = true;
        check_holes(k, spec, samples, feed->command_end_s - test.feed_in_mm / speed, run.data_end_s,
                    feed->command_end_s, omega, dir, max_hole_s);
        std::size_t i = feed->index;
        while (i < samples.size() && samples[i].time_s < run.data_start_s) ++i;
        run.first_sample = i;
        double lo = 0.0, hi = 0.0;
        for (; i < samples.size() && samples[i].time_s <= run.data_end_s; ++i) {
            detail::FitPoint p;
            p.t = samples[i].time_s;
            p.y_um = (samples[i].measured_mm - test.radius_mm) * 1e3;
            p.travelled = omega * (p.t - feed->command_end_s);
            p.theta = spec.start_deg * kDeg + dir * p.travelled;
            p.cos_theta = std::cos(p.theta), p.sin_theta = std::sin(p.theta);
            p.dir = dir;
            p.run = static_cast<int>(k);
            lo = i == run.first_sample ? p.y_um : std::min(lo, p.y_um);
            hi = i == run.first_sample ? p.y_um : std::max(hi, p.y_um);
            if (i > run.first_sample) steps.push_back(p.t - samples[i - 1].time_s);
            in.points.push_back(p);
        }
        run.last_sample = i;
        if (run.last_sample - run.first_sample < 10)
            throw CircularError(run_name(k, spec) + ": fewer than 10 samples in the data arc");
        run.radial_max_um = hi, run.radial_min_um = lo;
        in.run_lag_s.push_back(feed->lag_s);
        in.run_start_rad.push_back(spec.start_deg * kDeg);
        result.runs.push_back(run);
        while (from < samples.size() && samples[from].time_s < run_end_s) ++from;
    }
    std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
    in.sample_rate_hz = 1.0 / steps[steps.size() / 2];
    in.both_directions = ccw && cw;
    result.sample_rate_hz = in.sample_rate_hz;
    result.samples_used = in.points.size();

    // The diagnosis leaves out the few samples within a guard time of each axis reversal: a step whose
    // modelled time is off by a millisecond would otherwise pass for a reversal spike. (G uses all.)
    // The points are moved, not copied (10⁵ samples: 4 MB): the fit's stay in order in `in.points`,
    // the guarded ones go to `guarded` for G.
    std::vector<detail::FitPoint> guarded;
    {
        const double guard_s = 0.003 + 1.0 / in.sample_rate_hz;
        std::vector<double> lag_phase_rad;  // each run's, once
        for (const double lag : in.run_lag_s) lag_phase_rad.push_back(std::atan(omega * lag));
        std::size_t kept = 0;
        for (std::size_t i = 0; i < in.points.size(); ++i) {
            const detail::FitPoint& p = in.points[i];
            const double actual = p.theta - p.dir * lag_phase_rad[static_cast<std::size_t>(p.run)];
            const double k = std::round(actual / (0.5 * kPi));
            if (std::abs(actual - k * 0.5 * kPi) / omega < guard_s) {
                guarded.push_back(p);
                continue;
            }
            in.points[kept++] = p;
        }
        in.points.resize(kept);
    }
    detail::FitOutput fit = detail::fit_diagnostics(in, options);
    const double lag_phase = std::atan(omega * fit.lag_mean_s);
    const double cos_lag = std::cos(lag_phase), sin_lag = std::sin(lag_phase);
    // All the points again, in time order (the fit's and the guarded, merged), each angle's cosine and
    // sine once; the runs follow one another in time.
    std::vector<AnglePoint> all;
    all.reserve(in.points.size() + guarded.size());
    std::vector<std::size_t> run_begin(result.runs.size() + 1, 0);
    {
        std::size_t a = 0, b = 0;
        int run = -1;
        while (a < in.points.size() || b < guarded.size()) {
            const bool from_fit = b == guarded.size() || (a < in.points.size() && in.points[a].t < guarded[b].t);
            const detail::FitPoint& p = from_fit ? in.points[a++] : guarded[b++];
            while (run < p.run) run_begin[static_cast<std::size_t>(++run)] = all.size();
            // cos and sin of θ − dir·φ from θ's and φ's (angle addition).
            all.push_back({p.y_um, p.cos_theta * cos_lag + p.dir * p.sin_theta * sin_lag,
                           p.sin_theta * cos_lag - p.dir * p.cos_theta * sin_lag});
        }
        while (run < static_cast<int>(result.runs.size())) run_begin[static_cast<std::size_t>(++run)] = all.size();
    }
    for (std::size_t k = 0; k < result.runs.size(); ++k)
        result.runs[k].circularity_um = circular_deviation(all.data() + run_begin[k], all.data() + run_begin[k + 1]);
    if (in.both_directions) {
        const Eigen::Vector3d both = least_squares_circle(all.data(), all.data() + all.size());  // G(b)'s, and H's
        result.bidirectional_um = spread_about(all.data(), all.data() + all.size(), both);
        // H between the first run of each direction.
        const std::size_t none = result.runs.size();
        std::size_t run_ccw = none, run_cw = none;
        for (std::size_t k = 0; k < result.runs.size(); ++k) {
            if (result.runs[k].direction == Direction::Ccw && run_ccw == none) run_ccw = k;
            if (result.runs[k].direction == Direction::Cw && run_cw == none) run_cw = k;
        }
        if (run_ccw != none && run_cw != none)
            result.hysteresis_um =
                circular_hysteresis(all.data() + run_begin[run_ccw], all.data() + run_begin[run_ccw + 1],
                                    all.data() + run_begin[run_cw], all.data() + run_begin[run_cw + 1], both);
    }
    result.radial_max_um = result.runs.front().radial_max_um;
    result.radial_min_um = result.runs.front().radial_min_um;
    for (const auto& r : result.runs) {
        result.radial_max_um = std::max(result.radial_max_um, r.radial_max_um);
        result.radial_min_um = std::min(result.radial_min_um, r.radial_min_um);
    }
    model_curves(in, fit, cos_lag, sin_lag, result);
    result.diagnostics = std::move(fit.diagnostics);
    std::stable_sort(
        result.diagnostics.begin(), result.diagnostics.end(),
        [](const DiagnosticResult& a, const DiagnosticResult& b) { return a.contribution_um > b.contribution_um; });
    result.unseparable = std::move(fit.unseparable);
    result.residual_rms_um = fit.residual_rms_um;
    result.mean_radius_um = fit.mean_radius_um;
    result.mean_radius_std_um = fit.mean_radius_std_um;
    return result;
}

}  // namespace ballbar::analysis::circular
