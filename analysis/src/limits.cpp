// SPDX-License-Identifier: MIT
#include "ballbar/analysis/limits.hpp"

#include <charconv>
#include <cmath>

namespace ballbar::analysis::limits {
namespace {

std::string with_unit(std::string text, std::string_view unit) {
    if (!unit.empty()) text.append(" ").append(unit);
    return text;
}

}  // namespace

std::string number_text(double value) {
    // The shortest text that reads back, in fixed notation where that stays short ("200000", not
    // "2e+05"), scientific beyond ("1e+308", "1e-300").
    const double mag = std::abs(value);
    const bool fixed = value == 0 || (mag >= 1e-5 && mag < 1e16);
    char buf[64];
    const auto res = fixed ? std::to_chars(buf, buf + sizeof buf, value, std::chars_format::fixed)
                           : std::to_chars(buf, buf + sizeof buf, value, std::chars_format::scientific);
    return res.ec == std::errc() ? std::string(buf, res.ptr) : std::string("?");
}

std::string check_in(double value, double lo, double hi, std::string_view unit) {
    if (!std::isfinite(value)) return "is not a finite number";
    if (value >= lo && value <= hi) return {};
    return with_unit("= " + number_text(value) + " is outside [" + number_text(lo) + ", " + number_text(hi) + "]",
                     unit);
}

std::string check_above(double value, double lo, double hi, std::string_view unit) {
    if (!std::isfinite(value)) return "is not a finite number";
    if (value > lo && value <= hi) return {};
    return with_unit("= " + number_text(value) + " must be > " + number_text(lo) + " and <= " + number_text(hi), unit);
}

std::string check_integer_in(double value, double lo, double hi) {
    if (!std::isfinite(value)) return "is not a finite number";
    if (value == std::floor(value) && value >= lo && value <= hi) return {};
    return "= " + number_text(value) + " is not an integer in [" + number_text(lo) + ", " + number_text(hi) + "]";
}

double param_limit(ParamUnit unit) {
    switch (unit) {
        case ParamUnit::mm:
            return 1000;
        case ParamUnit::rad:
            return kPi;
        case ParamUnit::mm_per_mm:
            return 0.1;
        case ParamUnit::mm_per_h:
            return 1000;
        case ParamUnit::per_K:
            return 0.01;
    }
    return 0;
}

std::string check_param(Param p, double value) {
    const ParamUnit unit = param_info(p).unit;
    const double lim = param_limit(unit);
    return check_in(value, -lim, lim, to_string(unit));
}

}  // namespace ballbar::analysis::limits
