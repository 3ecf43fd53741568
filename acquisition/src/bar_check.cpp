// SPDX-License-Identifier: MIT
#include "ballbar/acquisition/bar_check.hpp"

#include <cmath>
#include <cstdio>

namespace ballbar::acquisition {

namespace {

std::string mm(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3f", v);
    std::string s = buf;
    while (s.back() == '0') s.pop_back();  // 150.000 → 150, 99.950 → 99.95
    if (s.back() == '.') s.pop_back();
    return s;
}

}  // namespace

std::string bar_length_mismatch(double plan_mm, double calibrated_mm, double tolerance_mm, std::string_view plan_file) {
    if (std::isfinite(plan_mm) && std::isfinite(calibrated_mm) && std::abs(calibrated_mm - plan_mm) <= tolerance_mm)
        return {};
    const std::string where =
        plan_file.empty() ? "a plan file (--plan FILE)" : "the plan file " + std::string(plan_file);
    return "bar length mismatch: the plan is for a " + mm(plan_mm) + " mm bar, the instrument's bar is calibrated at " +
           mm(calibrated_mm) + " mm (more than " + mm(tolerance_mm) + " mm apart). Fix: mount and calibrate the " +
           mm(plan_mm) + " mm bar, or measure with this one by setting \"bar_length_mm\": " + mm(calibrated_mm) +
           " in " + where + ".";
}

}  // namespace ballbar::acquisition
