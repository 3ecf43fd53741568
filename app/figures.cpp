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

/// "(-7.52, -20.71, 3.70) ± (0.05, 0.05, 0.04) µm" from mm: two significant digits of the smallest
/// uncertainty fix the decimals (2 to 4).
std::string vec_um(const analysis::Vec3& v, const analysis::Vec3* std) {
    int decimals = 2;
    if (std) {
        double smallest = 0;
        for (int a = 0; a < 3; ++a) {
            const double s = (*std)[a] * 1e3;
            if (s > 0 && (smallest == 0 || s < smallest)) smallest = s;
        }
        if (smallest > 0) decimals = std::clamp(1 - static_cast<int>(std::floor(std::log10(smallest))), 2, 4);
    }
    char buf[200];
    std::snprintf(buf, sizeof buf, "(%.*f, %.*f, %.*f)", decimals, v.x() * 1e3, decimals, v.y() * 1e3, decimals,
                  v.z() * 1e3);
    std::string out = buf;
    if (std) {
        std::snprintf(buf, sizeof buf, " ± (%.*f, %.*f, %.*f)", decimals, std->x() * 1e3, decimals, std->y() * 1e3,
                      decimals, std->z() * 1e3);
        out += buf;
    }
    return out + " µm";
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

/// A held parameter's effect an estimate carries by this share or more is said on screen (the rest is
/// in `--json`'s numbers and moves the estimate by less than a tenth of what the held one does).
constexpr double kCarriedShare = 0.1;

std::string fit_report(const ba::FitSummary& fit) {
    std::ostringstream os;
    char line[320];
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
            std::string held;
            for (const auto& c : e.carries)
                if (std::abs(c.share) >= kCarriedShare) held += (held.empty() ? "" : ", ") + c.name;
            std::snprintf(line, sizeof line, "  %-10s %28s  (independence %.2f)%s\n", e.name.c_str(),
                          with_uncertainty(e.estimate * u.factor, e.std * u.factor, u.symbol).c_str(), e.independence,
                          held.empty() ? "" : ("  with " + held + " at 0: not the machine's alone").c_str());
        } else {
            std::snprintf(line, sizeof line, "  %-10s unobservable (independence %.2f), held at %s\n", e.name.c_str(),
                          e.independence, with_uncertainty(e.estimate * u.factor, 0, u.symbol).c_str());
        }
        os << line;
    }
    os << carried_note(fit);
    return os.str();
}

std::string carried_note(const ba::FitSummary& fit) {
    std::vector<std::string> held, carriers;
    for (const auto& e : fit.estimates)
        for (const auto& c : e.carries) {
            if (std::abs(c.share) < kCarriedShare) continue;
            if (std::find(held.begin(), held.end(), c.name) == held.end()) held.push_back(c.name);
            if (e.param && std::find(carriers.begin(), carriers.end(), e.name) == carriers.end())
                carriers.push_back(e.name);
        }
    if (held.empty() || carriers.empty()) return {};
    const auto list = [](const std::vector<std::string>& v) {
        std::string out;
        for (std::size_t i = 0; i < v.size(); ++i) out += (i == 0 ? "" : i + 1 == v.size() ? " and " : ", ") + v[i];
        return out;
    };
    std::ostringstream os;
    os << "  These readings cannot determine " << list(held) << " (held at 0): " << list(carriers)
       << " carry their effect, so only combinations are known — each value above is the machine's plus "
          "what the held ones really are times:\n";
    for (const auto& e : fit.estimates) {
        if (!e.param || std::none_of(e.carries.begin(), e.carries.end(),
                                     [](const auto& c) { return std::abs(c.share) >= kCarriedShare; }))
            continue;
        const ScreenUnit u = screen_unit(ba::param_info(*e.param).unit);
        os << "    " << e.name << ":";
        for (const auto& c : e.carries) {
            if (std::abs(c.share) < kCarriedShare) continue;
            const ba::ParamEstimate* h = fit.find(c.name);
            const ScreenUnit hu = h && h->param ? screen_unit(ba::param_info(*h->param).unit) : ScreenUnit{1e3, "µm"};
            char buf[120];
            std::snprintf(buf, sizeof buf, " %+.3g %s per %s of %s", c.per_unit * u.factor / hu.factor,
                          std::string(u.symbol).c_str(), std::string(hu.symbol).c_str(), c.name.c_str());
            os << buf;
        }
        os << '\n';
    }
    os << "  The model reproduces what was measured (compensation with it is right at these poses); the "
          "values alone are not the machine's. docs/identification.md (Observability) says what each "
          "cannot separate and what measurement would.\n";
    return os.str();
}

}  // namespace ballbar::app
