// SPDX-License-Identifier: MIT
#include "format.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <ctime>

#include "ballbar/analysis/types.hpp"

namespace ballbar::report {

std::string given(double v) {
    return fmt::format("{}", v);
}

std::string fixed(double v, int decimals) {
    if (!std::isfinite(v)) return "n/a";
    std::string s = fmt::format("{:.{}f}", v, decimals);
    if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
    return s;
}

std::string fixed(const std::optional<double>& v, int decimals, const std::string& missing) {
    return v ? fixed(*v, decimals) : missing;
}

int uncertainty_decimals(double u, int decimals) {
    u = std::abs(u);
    while (u > 0 && decimals < 4 && u < 0.5 * std::pow(10.0, -decimals)) ++decimals;
    return decimals;
}

std::string plus_minus(double v, const std::optional<double>& u, int decimals) {
    if (!u || !std::isfinite(*u)) return fixed(v, decimals);
    return fixed(v, decimals) + " ± " + fixed(std::abs(*u), uncertainty_decimals(*u, decimals));
}

std::string degrees(const std::optional<double>& rad) {
    if (!rad) return "–";
    return fixed(analysis::rad_to_deg(*rad), kDegDecimals) + "°";
}

std::string arcseconds(const std::optional<double>& rad, int decimals) {
    if (!rad) return "–";
    return fixed(analysis::rad_to_arcsec(*rad), decimals) + "″";
}

std::string clock_time(double seconds) {
    if (!std::isfinite(seconds)) return "n/a";
    const bool neg = seconds < 0;
    auto s = static_cast<long long>(std::llround(std::abs(seconds)));
    const long long h = s / 3600, m = (s / 60) % 60;
    s %= 60;
    const std::string t = h > 0 ? fmt::format("{}:{:02}:{:02}", h, m, s) : fmt::format("{}:{:02}", m, s);
    return neg ? "-" + t : t;
}

std::string range_C(const Range& r) {
    if (!r.present()) return "not recorded";
    std::string s = fixed(*r.mean, 2) + " °C";
    if (r.min && r.max) s += " (" + fixed(*r.min, 2) + " to " + fixed(*r.max, 2) + ")";
    return s;
}

std::string or_dash(const std::string& s) {
    return s.empty() ? "–" : s;
}

std::string local_time(const std::string& utc_iso) {
    if (utc_iso.empty()) return "–";
    std::tm t{};
    int sec = 0;
    if (std::sscanf(utc_iso.c_str(), "%4d-%2d-%2dT%2d:%2d:%2d", &t.tm_year, &t.tm_mon, &t.tm_mday, &t.tm_hour,
                    &t.tm_min, &sec) != 6 ||
        utc_iso.back() != 'Z')
        return utc_iso;
    t.tm_year -= 1900;
    t.tm_mon -= 1;
    t.tm_sec = sec;
    const std::time_t when = timegm(&t);
    std::tm local{};
    if (when == static_cast<std::time_t>(-1) || !localtime_r(&when, &local)) return utc_iso;
    char text[40];
    if (std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S %z", &local) == 0) return utc_iso;
    std::string out = text;  // "+0100" → "+01:00"
    if (out.size() >= 5) out.insert(out.size() - 2, ":");
    return out;
}

}  // namespace ballbar::report
