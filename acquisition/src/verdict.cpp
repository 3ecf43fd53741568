// SPDX-License-Identifier: MIT
#include "ballbar/acquisition/verdict.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "ballbar/acquisition/plan.hpp"
#include "ballbar/analysis/types.hpp"

namespace ballbar::acquisition {

namespace {

std::string fixed(double v, int decimals) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    return buf;
}

/// A tolerance as given (20, 0.5, 12.5): no trailing zeros.
std::string given(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

/// "the location", "both locations", "all 8 locations".
std::string all_of(std::size_t n, const std::string& noun) {
    if (n == 1) return "the " + noun;
    if (n == 2) return "both " + noun + "s";
    return "all " + std::to_string(n) + " " + noun + "s";
}

}  // namespace

bool SsmVerdict::pass() const {
    if (checks.empty()) return false;
    for (const Check& c : checks)
        if (!c.pass()) return false;
    return true;
}

std::string SsmVerdict::summary() const {
    if (checks.empty()) return "";
    std::size_t locations = 0, angles = 0;
    // Each kind's smallest and largest tolerance: one value, or the tests' own between them.
    std::optional<double> location_lo, location_hi, angle_lo, angle_hi;
    std::vector<const Check*> failed;
    for (const Check& c : checks) {
        const bool is_location = c.unit == "µm";
        (is_location ? locations : angles) += 1;
        auto& lo = is_location ? location_lo : angle_lo;
        auto& hi = is_location ? location_hi : angle_hi;
        lo = std::min(lo.value_or(c.tolerance), c.tolerance);
        hi = std::max(hi.value_or(c.tolerance), c.tolerance);
        if (!c.pass()) failed.push_back(&c);
    }
    auto within = [](double lo, double hi, const char* unit) {
        return lo == hi ? "within " + given(lo) + unit
                        : "within each test's tolerance (" + given(lo) + " to " + given(hi) + unit + ")";
    };
    if (failed.empty()) {
        std::string s = "PASS:";
        if (location_lo)
            s += " |ΔV| " + within(*location_lo, *location_hi, " µm") + " at " + all_of(locations, "location");
        if (angle_lo)
            s += std::string(location_lo ? ";" : "") + " " + all_of(angles, "orientation error") + " " +
                 within(*angle_lo, *angle_hi, "″");
        return s;
    }
    std::string s =
        "FAIL: " + std::to_string(failed.size()) + " of " + std::to_string(checks.size()) + " beyond tolerance —";
    for (std::size_t i = 0; i < failed.size(); ++i) {
        const Check& c = *failed[i];
        s += (i ? "; test " : " test ") + std::to_string(c.test) + " " + c.figure + " " + fixed(c.value, 2) +
             (c.unit == "µm" ? " µm" : "″") + " > " + given(c.tolerance) + (c.unit == "µm" ? " µm" : "″");
    }
    return s;
}

SsmVerdict judge_ssm(analysis::MachineType type, const Tolerances& machine, const std::vector<TestSpec>& plan_tests,
                     const std::vector<TestResult>& tests) {
    SsmVerdict v;
    for (const TestResult& t : tests) {
        Tolerances tol = machine;  // the test's own, where the plan gives them
        if (t.test >= 0 && static_cast<std::size_t>(t.test) < plan_tests.size()) {
            const Tolerances& own = plan_tests[static_cast<std::size_t>(t.test)].tolerances;
            if (own.location_um) tol.location_um = own.location_um;
            if (own.angle_arcsec) tol.angle_arcsec = own.angle_arcsec;
        }
        if (tol.location_um) {
            v.checks.push_back({t.test + 1, "|ΔV1|", t.dV1_mm.norm() * 1e3, *tol.location_um, "µm"});
            v.checks.push_back({t.test + 1, "|ΔV2|", t.dV2_mm.norm() * 1e3, *tol.location_um, "µm"});
        }
        if (tol.angle_arcsec && t.orientation.exact) {
            const auto& e = *t.orientation.exact;
            const analysis::MeasuredAngles angles = measured_angles(type, t.kind);
            auto add = [&](const char* name, double rad) {
                v.checks.push_back({t.test + 1, name, std::abs(analysis::rad_to_arcsec(rad)), *tol.angle_arcsec, "″"});
            };
            if (angles.alpha) add("Δα", e.d_alpha_rad);
            if (angles.beta) add("Δβ", e.d_beta_rad);
            if (angles.gamma) add("Δγ", e.d_gamma_rad);
        }
    }
    return v;
}

}  // namespace ballbar::acquisition
