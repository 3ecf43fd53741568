// SPDX-License-Identifier: MIT
#include "figures.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace ballbar::app {

namespace ba = ballbar::analysis;

ScreenUnit screen_unit(ba::ParamUnit unit) {
    switch (unit) {
        case ba::ParamUnit::mm:
            return {1e3, "µm"};
        case ba::ParamUnit::rad:
            return {1e6, "µrad"};
        case ba::ParamUnit::mm_per_mm:
            return {1e6, "µm/m"};
        case ba::ParamUnit::mm_per_h:
            return {1e3, "µm/h"};
        case ba::ParamUnit::per_K:
            return {1e6, "µm/m/K"};
    }
    return {1, "?"};
}

std::string count_of(std::size_t n, std::string_view noun) {
    return std::to_string(n) + " " + std::string(noun) + (n == 1 ? "" : "s");
}

std::string with_uncertainty(double value, double std, std::string_view unit) {
    char buf[96];
    if (!(std > 0) || !std::isfinite(std) || !std::isfinite(value)) {
        std::snprintf(buf, sizeof buf, "%.4g %.*s", value, static_cast<int>(unit.size()), unit.data());
        return buf;
    }
    // Two significant digits of the uncertainty fix the last digit shown of both.
    const int exponent = static_cast<int>(std::floor(std::log10(std)));
    const int decimals = std::clamp(1 - exponent, 0, 12);
    std::snprintf(buf, sizeof buf, "%.*f ± %.*f %.*s", decimals, value, decimals, std, static_cast<int>(unit.size()),
                  unit.data());
    return buf;
}

std::optional<double> sigma_off(double value, double std, double truth) {
    if (!(std > 0) || !std::isfinite(std) || !std::isfinite(value) || !std::isfinite(truth)) return std::nullopt;
    const double n = std::abs(value - truth) / std;
    if (n > kFlagSigma) return n;
    return std::nullopt;
}

std::string sigma_flag(double value, double std, double truth, std::string_view what) {
    const auto n = sigma_off(value, std, truth);
    if (!n) return {};
    char buf[96];
    std::snprintf(buf, sizeof buf, "  !! %.1fσ from %.*s", *n, static_cast<int>(what.size()), what.data());
    return buf;
}

std::string estimate_text(const ba::ParamEstimate& e) {
    const ScreenUnit u = e.param ? screen_unit(ba::param_info(*e.param).unit) : ScreenUnit{1e3, "µm"};
    return e.name + "  " + with_uncertainty(e.estimate * u.factor, e.std * u.factor, u.symbol);
}

std::string fit_report(const ba::FitSummary& fit) {
    std::ostringstream os;
    char line[200];
    std::snprintf(line, sizeof line,
                  "%s after %d iterations (%s); %zu readings, residual RMS %.3f µm (start %.3f µm)\n",
                  fit.converged ? "converged" : "NOT converged", fit.iterations, fit.message.c_str(), fit.readings,
                  fit.residual_rms_mm * 1e3, fit.initial_rms_mm * 1e3);
    os << line;
    if (fit.uncertainty_from_floor) {
        std::snprintf(line, sizeof line,
                      "  the residual (σ %.4f µm) is below the readings' own noise (%.4f µm): the uncertainties "
                      "assume the latter\n",
                      fit.residual_sigma_mm * 1e3, fit.noise_floor_mm * 1e3);
        os << line;
    }
    for (const auto& e : fit.estimates) {
        const ScreenUnit u = e.param ? screen_unit(ba::param_info(*e.param).unit) : ScreenUnit{1e3, "µm"};
        if (e.observable) {
            std::snprintf(line, sizeof line, "  %-10s %28s  (independence %.2f)\n", e.name.c_str(),
                          with_uncertainty(e.estimate * u.factor, e.std * u.factor, u.symbol).c_str(), e.independence);
        } else {
            std::snprintf(line, sizeof line, "  %-10s unobservable (independence %.2f), held at %s\n", e.name.c_str(),
                          e.independence, with_uncertainty(e.estimate * u.factor, 0, u.symbol).c_str());
        }
        os << line;
    }
    return os.str();
}

}  // namespace ballbar::app
