// SPDX-License-Identifier: MIT
// The noise floor of the readings and the verdict on a residual: is it noise or structure?
// (docs/discovery.md, "Noise floor and verdict").
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <tuple>

#include "ballbar/analysis/discovery.hpp"

namespace ballbar::analysis {
namespace {

/// Regularized lower incomplete gamma P(a, x) by its series (x < a + 1).
double gamma_series(double a, double x) {
    double sum = 1.0 / a, term = sum;
    for (int k = 1; k < 1000000; ++k) {
        term *= x / (a + k);
        sum += term;
        if (std::abs(term) < std::abs(sum) * 1e-16) break;
    }
    return std::exp(-x + a * std::log(x) - std::lgamma(a)) * sum;
}

/// Regularized upper incomplete gamma Q(a, x) by its continued fraction (x ≥ a + 1), modified Lentz.
double gamma_continued_fraction(double a, double x) {
    constexpr double kTiny = 1e-300;
    double b = x + 1.0 - a, c = 1.0 / kTiny, d = 1.0 / b, h = d;
    for (int i = 1; i < 1000000; ++i) {
        const double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if (std::abs(d) < kTiny) d = kTiny;
        c = b + an / c;
        if (std::abs(c) < kTiny) c = kTiny;
        d = 1.0 / d;
        const double del = d * c;
        h *= del;
        if (std::abs(del - 1.0) < 1e-16) break;
    }
    return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

}  // namespace

double chi_square_sf(double x, double dof) {
    if (!(dof > 0)) throw AnalysisError("chi-square distribution: degrees of freedom must be positive");
    if (std::isnan(x) || x <= 0) return 1.0;
    if (std::isinf(x)) return 0.0;
    const double a = dof / 2.0, h = x / 2.0;
    return h < a + 1.0 ? 1.0 - gamma_series(a, h) : gamma_continued_fraction(a, h);
}

double f_critical(double alpha, double d1, double d2) {
    double lo = 0, hi = 1;
    while (f_distribution_sf(hi, d1, d2) > alpha && hi < 1e12) hi *= 2;
    for (int i = 0; i < 100 && hi - lo > 1e-9 * hi; ++i) {
        const double mid = 0.5 * (lo + hi);
        (f_distribution_sf(mid, d1, d2) > alpha ? lo : hi) = mid;
    }
    return hi;
}

namespace {
/// The floor the data give (the user's figure, the within-point spread, repeated points).
NoiseFloor floor_from_data(const ReadingSet& readings, const Eigen::VectorXd& residual_mm,
                           std::optional<double> user_mm);
}  // namespace

NoiseFloor estimate_noise_floor(const ReadingSet& readings, const Eigen::VectorXd& residual_mm,
                                std::optional<double> user_mm, std::optional<double> resolution_mm) {
    NoiseFloor f = floor_from_data(readings, residual_mm, user_mm);
    if (user_mm || !resolution_mm || !(*resolution_mm > 0)) return f;
    // A reading averaged from many samples can look quieter than the instrument resolves; what is
    // below its quantisation (resolution/√12) is not structure the readings can show.
    const double quantum = *resolution_mm / std::sqrt(12.0);
    if (f.sigma_mm < quantum) {
        char text[200];
        std::snprintf(text, sizeof text, "%s; raised to the instrument's resolution %.3g µm / √12", f.detail.c_str(),
                      *resolution_mm * 1e3);
        f.sigma_mm = quantum;
        f.detail = text;
        f.raised_to_resolution = true;
        if (f.source == "unknown") f.source = "resolution";
    }
    return f;
}

namespace {

NoiseFloor floor_from_data(const ReadingSet& readings, const Eigen::VectorXd& residual_mm,
                           std::optional<double> user_mm) {
    NoiseFloor f;
    char text[160];
    if (user_mm) {
        if (!(*user_mm > 0) || !std::isfinite(*user_mm)) throw AnalysisError("the noise figure must be positive");
        f.sigma_mm = *user_mm;
        f.source = "given";
        f.detail = "the user's figure";
        return f;
    }
    // The readings' own within-point spread: each reading is the mean of n samples with standard
    // deviation std_mm, so its own noise is std_mm/√n (std_mm itself when n is not given).
    double sum = 0;
    std::size_t count = 0;
    int n_min = 0, n_max = 0;
    for (const Reading& r : readings.readings) {
        if (!r.std_mm || !(*r.std_mm > 0) || !std::isfinite(*r.std_mm)) continue;
        const int n = std::max(r.n, 1);
        sum += *r.std_mm * *r.std_mm / n;
        n_min = count == 0 ? n : std::min(n_min, n);
        n_max = std::max(n_max, n);
        ++count;
    }
    if (count > 0 && 2 * count >= readings.readings.size()) {
        f.sigma_mm = std::sqrt(sum / static_cast<double>(count));
        f.source = "within-point spread";
        if (n_min == n_max)
            std::snprintf(text, sizeof text, "std_mm/sqrt(n) of %zu readings, n = %d", count, n_min);
        else
            std::snprintf(text, sizeof text, "std_mm/sqrt(n) of %zu readings, n = %d..%d", count, n_min, n_max);
        f.detail = text;
        return f;
    }
    // Repeated points: readings at the same socket and pose; the spread of their residuals about
    // their group's mean.
    if (residual_mm.size() == static_cast<Eigen::Index>(readings.readings.size())) {
        using Key = std::tuple<long long, long long, long long, long long, long long, long long, long long, long long,
                               long long>;
        auto q = [](double v) { return static_cast<long long>(std::llround(v * 1e6)); };
        std::map<Key, std::pair<std::vector<double>, int>> groups;
        for (std::size_t i = 0; i < readings.readings.size(); ++i) {
            const Reading& r = readings.readings[i];
            const Key k{q(r.pose.X_mm),  q(r.pose.Y_mm),     q(r.pose.Z_mm),     q(r.pose.A_rad),   q(r.pose.B_rad),
                        q(r.pose.C_rad), q(r.socket_mm.x()), q(r.socket_mm.y()), q(r.socket_mm.z())};
            groups[k].first.push_back(residual_mm[static_cast<Eigen::Index>(i)]);
        }
        double ss = 0, dof = 0;
        std::size_t repeated = 0;
        for (const auto& [k, g] : groups) {
            const auto& v = g.first;
            if (v.size() < 2) continue;
            double mean = 0;
            for (double x : v) mean += x;
            mean /= static_cast<double>(v.size());
            for (double x : v) ss += (x - mean) * (x - mean);
            dof += static_cast<double>(v.size() - 1);
            ++repeated;
        }
        if (dof >= 10) {
            f.sigma_mm = std::sqrt(ss / dof);
            f.source = "repeated points";
            std::snprintf(text, sizeof text, "%zu points measured more than once, %.0f degrees of freedom", repeated,
                          dof);
            f.detail = text;
            return f;
        }
    }
    f.source = "unknown";
    f.detail = "no n/std_mm in the readings, no repeated points, no figure given (--noise-um)";
    return f;
}

}  // namespace

NoiseVerdict noise_verdict(const Eigen::VectorXd& residual_mm, double fitted_unknowns, const NoiseFloor& floor,
                           double alpha) {
    NoiseVerdict v;
    v.alpha = alpha;
    const auto n = static_cast<double>(residual_mm.size());
    v.rms_mm = n > 0 ? std::sqrt(residual_mm.squaredNorm() / n) : 0.0;
    v.dof = std::max(n - fitted_unknowns, 1.0);
    v.floor_known = floor.known();
    if (!v.floor_known) {
        v.text = "noise floor unknown";
        return v;
    }
    v.ratio = v.rms_mm / floor.sigma_mm;
    v.chi2 = residual_mm.squaredNorm() / (floor.sigma_mm * floor.sigma_mm);
    v.p_value = chi_square_sf(v.chi2, v.dof);
    v.structure = v.p_value < alpha;
    v.text = v.structure ? "unexplained structure" : "consistent with noise";
    return v;
}

}  // namespace ballbar::analysis
