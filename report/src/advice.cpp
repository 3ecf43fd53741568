// SPDX-License-Identifier: MIT
#include "ballbar/report/advice.hpp"

#include <fmt/format.h>

#include <cctype>
#include <cmath>

namespace ballbar::report {
namespace {

bool starts_with(const std::string& s, const char* prefix) {
    return s.rfind(prefix, 0) == 0;
}

/// The axis letter of a per-axis key ("backlash_x_um" → 'X'), or 0.
char axis_of(const std::string& key, const char* prefix) {
    const std::string p(prefix);
    if (!starts_with(key, prefix) || key.size() < p.size() + 1) return 0;
    return static_cast<char>(std::toupper(static_cast<unsigned char>(key[p.size()])));
}

}  // namespace

std::string diagnostic_action(const std::string& key, double value, double std_uncertainty, const std::string& plane) {
    if (!std::isfinite(value) || std::abs(value) <= 2 * std::abs(std_uncertainty)) return "";
    const char p = plane.size() == 2 ? plane[0] : 'P', q = plane.size() == 2 ? plane[1] : 'Q';
    const double a = std::abs(value);
    if (const char ax = axis_of(key, "backlash_")) {
        if (value >= 0)
            return fmt::format("raise {}'s backlash compensation by {:.1f} µm (lost motion at each reversal of {})", ax,
                               a, ax);
        return fmt::format("lower {}'s backlash compensation by {:.1f} µm: it over-compensates", ax, a);
    }
    if (const char ax = axis_of(key, "reversal_spike_"))
        return fmt::format(
            "{} sticks for a moment at each reversal ({:.1f} µm): adjust {}'s reversal (friction) compensation or "
            "its servo tuning, and check its lubrication",
            ax, a, ax);
    if (key == "squareness_um_per_m")
        return fmt::format(
            "{} and {} are out of square by {:.1f} µm/m ({:.1f}″, the angle between +{} and +{} {} 90°): realign "
            "the axes, or enter it in the controller's squareness compensation",
            p, q, a, a * 0.206264806, p, q, value > 0 ? "under" : "over");
    if (key == "scale_mismatch_ppm")
        return fmt::format(
            "{} travels {:.1f} ppm {} than {} ({:.1f} µm per 100 mm): correct one axis's linear (pitch) compensation, "
            "or look for thermal growth",
            p, a, value > 0 ? "further" : "less far", q, a * 0.1);
    if (key == "servo_mismatch_ms")
        return fmt::format("{} lags {} by {:.2f} ms: match the two axes' position-loop gains (and feed-forward)",
                           value > 0 ? p : q, value > 0 ? q : p, a);
    if (const char ax = axis_of(key, "cyclic_error_"))
        return fmt::format("a cyclic error of {:.1f} µm along {}: check {}'s ballscrew, its bearings and the encoder",
                           a, ax, ax);
    if (const char ax = axis_of(key, "straightness_"))
        return fmt::format(
            "{}'s travel bows by {:.1f} µm over the circle: check the straightness of its guideways and the "
            "machine's levelling",
            ax, a);
    if (key == "vibration_um")
        return fmt::format(
            "a vibration of {:.1f} µm: check the servo tuning, what is loose (the ball-bar's mounts first), and what "
            "runs nearby",
            a);
    return "";
}

}  // namespace ballbar::report
