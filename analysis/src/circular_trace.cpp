// SPDX-License-Identifier: MIT
// Circular test: names, the test specification's checks, the diagnostics' keys and radial scales, and
// finding a run's feed-in in the trace (a ramp of feed_in_mm at the feed, through a first-order lag).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "ballbar/analysis/circular.hpp"
#include "ballbar/analysis/limits.hpp"

namespace ballbar::analysis::circular {

const char* plane_name(Plane plane) {
    switch (plane) {
        case Plane::XY:
            return "XY";
        case Plane::YZ:
            return "YZ";
        case Plane::ZX:
            return "ZX";
    }
    return "?";
}

std::optional<Plane> parse_plane(const std::string& text) {
    if (text == "XY") return Plane::XY;
    if (text == "YZ") return Plane::YZ;
    if (text == "ZX") return Plane::ZX;
    return std::nullopt;
}

const char* direction_name(Direction direction) {
    return direction == Direction::Ccw ? "ccw" : "cw";
}

std::optional<Direction> parse_direction(const std::string& text) {
    if (text == "ccw") return Direction::Ccw;
    if (text == "cw") return Direction::Cw;
    return std::nullopt;
}

std::array<char, 2> plane_axes(Plane plane) {
    switch (plane) {
        case Plane::XY:
            return {'x', 'y'};
        case Plane::YZ:
            return {'y', 'z'};
        case Plane::ZX:
            return {'z', 'x'};
    }
    return {'x', 'y'};
}

std::array<int, 2> plane_axis_index(Plane plane) {
    switch (plane) {
        case Plane::XY:
            return {0, 1};
        case Plane::YZ:
            return {1, 2};
        case Plane::ZX:
            return {2, 0};
    }
    return {0, 1};
}

std::string TestSpec::validate() const {
    namespace lim = limits;
    auto bad = [](const char* key, const std::string& why) { return why.empty() ? why : key + (" " + why); };
    if (auto why = bad("radius_mm", lim::check_above(radius_mm, 0.0, lim::kLength_mm, "mm")); !why.empty()) return why;
    if (auto why = bad("feed_mm_min", lim::check_in(feed_mm_min, lim::kFeedMin_mm_min, lim::kFeedMax_mm_min, "mm/min"));
        !why.empty())
        return why;
    if (auto why = bad("feed_in_mm", lim::check_above(feed_in_mm, 0.0, lim::kSmallLength_mm, "mm")); !why.empty())
        return why;
    if (feed_in_mm >= radius_mm) return "feed_in_mm must be smaller than radius_mm";
    for (std::size_t i = 0; i < centre_mm.size(); ++i)
        if (auto why = lim::check_in(centre_mm[i], -lim::kPosition_mm, lim::kPosition_mm, "mm"); !why.empty())
            return "centre_mm[" + std::to_string(i) + "] " + why;
    if (runs.empty()) return "runs must list at least one run";
    for (std::size_t i = 0; i < runs.size(); ++i) {
        const RunSpec& r = runs[i];
        const std::string where = "runs[" + std::to_string(i) + "]: ";
        if (auto why = bad("start_deg", lim::check_in(r.start_deg, -lim::kRotary_deg, lim::kRotary_deg, "deg"));
            !why.empty())
            return where + why;
        if (auto why = bad("overshoot_deg", lim::check_in(r.overshoot_deg, 0.0, 360.0, "deg")); !why.empty())
            return where + why;
        if (auto why = bad("data_arc_deg", lim::check_in(r.data_arc_deg, 30.0, 360.0, "deg")); !why.empty())
            return where + why;
    }
    return {};
}

std::string diagnostic_key(Diag diag, Plane plane) {
    const auto axes = plane_axes(plane);
    const std::string p(1, axes[0]), q(1, axes[1]);
    switch (diag) {
        case Diag::BacklashP:
            return "backlash_" + p + "_um";
        case Diag::BacklashQ:
            return "backlash_" + q + "_um";
        case Diag::SpikeP:
            return "reversal_spike_" + p + "_um";
        case Diag::SpikeQ:
            return "reversal_spike_" + q + "_um";
        case Diag::Squareness:
            return "squareness_um_per_m";
        case Diag::ScaleMismatch:
            return "scale_mismatch_ppm";
        case Diag::ServoMismatch:
            return "servo_mismatch_ms";
        case Diag::CyclicP:
            return "cyclic_error_" + p + "_um";
        case Diag::CyclicPitchP:
            return "cyclic_pitch_" + p + "_mm";
        case Diag::CyclicQ:
            return "cyclic_error_" + q + "_um";
        case Diag::CyclicPitchQ:
            return "cyclic_pitch_" + q + "_mm";
        case Diag::StraightnessP:
            return "straightness_" + p + "_um";
        case Diag::StraightnessQ:
            return "straightness_" + q + "_um";
        case Diag::Vibration:
            return "vibration_um";
        case Diag::VibrationHz:
            return "vibration_hz";
    }
    return "?";
}

const char* diagnostic_unit(Diag diag) {
    switch (diag) {
        case Diag::Squareness:
            return "um_per_m";
        case Diag::ScaleMismatch:
            return "ppm";
        case Diag::ServoMismatch:
            return "ms";
        case Diag::CyclicPitchP:
        case Diag::CyclicPitchQ:
            return "mm";
        case Diag::VibrationHz:
            return "hz";
        default:
            return "um";
    }
}

const char* diagnostic_unit_symbol(Diag diag) {
    const std::string_view u = diagnostic_unit(diag);
    if (u == "um") return "µm";
    if (u == "um_per_m") return "µm/m";
    if (u == "hz") return "Hz";
    return diagnostic_unit(diag);
}

double radial_um_per_unit(Diag diag, const TestSpec& test) {
    const double speed_mm_s = test.feed_mm_min / 60.0;
    switch (diag) {
        case Diag::BacklashP:
        case Diag::BacklashQ:
            return 0.5;  // the trace steps by ±b/2 about the mean
        case Diag::SpikeP:
        case Diag::SpikeQ:
        case Diag::CyclicP:
        case Diag::CyclicQ:
        case Diag::Vibration:
            return 1.0;
        case Diag::Squareness:
        case Diag::ScaleMismatch:
            return test.radius_mm * 1e-3 / 2.0;  // R/2 · 1e-6, in µm
        case Diag::ServoMismatch:
            return speed_mm_s / 2.0;  // v·Δτ/2, µm per ms
        case Diag::StraightnessP:
        case Diag::StraightnessQ:
            return 2.0 / (3.0 * std::sqrt(3.0));  // max of cos²θ·sinθ
        case Diag::CyclicPitchP:
        case Diag::CyclicPitchQ:
        case Diag::VibrationHz:
            return 0.0;
    }
    return 0.0;
}

namespace {

/// Length fall of a ramp of `depth` at `speed` starting at u = 0, through a first-order lag `tau`.
double lagged_ramp(double u, double depth, double speed, double tau) {
    if (u <= 0.0) return 0.0;
    const double duration = depth / speed;
    if (tau < 1e-7) return std::min(u, duration) * speed;
    if (u <= duration) return speed * (u - tau * (1.0 - std::exp(-u / tau)));
    const double left = speed * tau * (1.0 - std::exp(-duration / tau));
    return depth - left * std::exp(-(u - duration) / tau);
}

double crossing_time(const std::vector<TraceSample>& s, std::size_t before, double level) {
    const TraceSample& a = s[before];
    const TraceSample& b = s[before + 1];
    const double span = b.measured_mm - a.measured_mm;
    if (span == 0.0) return a.time_s;
    const double f = std::clamp((level - a.measured_mm) / span, 0.0, 1.0);
    return a.time_s + f * (b.time_s - a.time_s);
}

}  // namespace

std::optional<FeedIn> find_feed_in(const TestSpec& test, const std::vector<TraceSample>& samples, std::size_t from) {
    const double speed = test.feed_mm_min / 60.0;
    const double depth = test.feed_in_mm;
    const double duration = depth / speed;
    const double high = test.radius_mm + 0.8 * depth;
    const double low = test.radius_mm + 0.2 * depth;
    std::size_t i = from;
    const std::size_t n = samples.size();
    while (i + 1 < n) {
        while (i < n && samples[i].measured_mm < high) ++i;  // standing out, before the move
        std::size_t last_high = i;
        std::size_t j = i;
        while (j < n && samples[j].measured_mm > low) {
            if (samples[j].measured_mm >= high) last_high = j;
            ++j;
        }
        if (j >= n || last_high + 1 >= n) return std::nullopt;
        const double t_high = crossing_time(samples, last_high, high);
        const double t_low = crossing_time(samples, j - 1, low);
        const double dt = samples[j].time_s - samples[j - 1].time_s;
        const double expected = 0.6 * duration;
        const double took = t_low - t_high;
        if (took < 0.3 * expected - 2.0 * dt || took > 3.0 * expected + 0.2 + 2.0 * dt) {
            i = j;  // not a move at the feed: look for the next fall
            continue;
        }
        // Fit the lagged ramp: parameters start time t0, lag tau, standing length.
        const double t_half = 0.5 * (t_high + t_low);
        std::size_t a = last_high;
        while (a > from && samples[a - 1].measured_mm > test.radius_mm + 0.98 * depth &&
               samples[a - 1].time_s > t_half - duration - 0.1)
            --a;
        std::size_t b = j;
        while (b + 1 < n && samples[b + 1].time_s < t_half + duration + 0.25) ++b;
        Eigen::Vector3d x(t_half - 0.5 * duration - 0.005, 0.005, samples[a].measured_mm);
        auto residuals = [&](const Eigen::Vector3d& prm, Eigen::VectorXd& r) {
            r.resize(static_cast<Eigen::Index>(b - a + 1));
            for (std::size_t k = a; k <= b; ++k)
                r[static_cast<Eigen::Index>(k - a)] =
                    samples[k].measured_mm -
                    (prm[2] - lagged_ramp(samples[k].time_s - prm[0], depth, speed, std::max(prm[1], 0.0)));
        };
        Eigen::VectorXd r, r2;
        residuals(x, r);
        double cost = r.squaredNorm();
        double lambda = 1e-3;
        for (int it = 0; it < 40; ++it) {
            Eigen::MatrixXd jac(r.size(), 3);
            const double steps[3] = {1e-6, 1e-6, 1e-6};
            for (int c = 0; c < 3; ++c) {
                Eigen::Vector3d xp = x;
                xp[c] += steps[c];
                residuals(xp, r2);
                jac.col(c) = (r2 - r) / steps[c];
            }
            Eigen::Matrix3d h = jac.transpose() * jac;
            const Eigen::Vector3d g = jac.transpose() * r;
            bool improved = false;
            for (int tries = 0; tries < 8 && !improved; ++tries) {
                Eigen::Matrix3d hd = h;
                hd.diagonal() *= 1.0 + lambda;
                const Eigen::Vector3d step = hd.ldlt().solve(-g);
                Eigen::Vector3d xn = x + step;
                xn[1] = std::clamp(xn[1], 0.0, 1.0);
                residuals(xn, r2);
                const double c2 = r2.squaredNorm();
                if (c2 <= cost) {
                    const double gain = cost - c2;
                    x = xn;
                    r = r2;
                    cost = c2;
                    lambda = std::max(lambda / 4.0, 1e-9);
                    improved = true;
                    if (gain <= 1e-12 * (cost + 1e-18)) it = 1000;
                } else {
                    lambda *= 8.0;
                }
            }
            if (!improved) break;
        }
        FeedIn found;
        found.command_end_s = x[0] + duration;
        found.lag_s = std::max(x[1], 0.0);
        found.standing_mm = x[2];
        std::size_t k = last_high;
        while (k < n && samples[k].time_s < t_half) ++k;
        found.index = k;
        return found;
    }
    return std::nullopt;
}

}  // namespace ballbar::analysis::circular
