// SPDX-License-Identifier: MIT
// How numbers appear in the report (PDF tables and figure notes). Plain ASCII "-" in tables so that a
// reader searching the text (pdftotext, grep) finds the numbers the JSON holds.
#pragma once

#include <optional>
#include <string>

#include "ballbar/report/report.hpp"

namespace ballbar::report {

inline constexpr int kUmDecimals = 2;      ///< µm
inline constexpr int kDegDecimals = 5;     ///< degrees
inline constexpr int kArcsecDecimals = 1;  ///< arcseconds

/// Fixed point; "-0.00" becomes "0.00"; non-finite values become "n/a".
std::string fixed(double v, int decimals);
std::string fixed(const std::optional<double>& v, int decimals, const std::string& missing = "–");
/// A value as the user gave it (a tolerance: 20, 12.5, 0.75): the shortest text, no trailing zeros.
std::string given(double v);
/// Decimals of an uncertainty shown next to a value with `decimals`: one more while it would round to
/// zero (down to 4), so that "± 0.00" never hides a small but known uncertainty.
int uncertainty_decimals(double u, int decimals);
/// "v ± u" (or just "v" without an uncertainty); u with uncertainty_decimals().
std::string plus_minus(double v, const std::optional<double>& u, int decimals);
/// An angle given in radians, shown in degrees / arcseconds with the unit sign.
std::string degrees(const std::optional<double>& rad);
std::string arcseconds(const std::optional<double>& rad, int decimals = kArcsecDecimals);
/// A session time: "m:ss" or "h:mm:ss".
std::string clock_time(double seconds);
/// A temperature range: "20.10 °C (20.00 to 20.20)", or "not recorded".
std::string range_C(const Range& r);
/// The text, or "–" when empty.
std::string or_dash(const std::string& s);
/// A stored UTC timestamp ("2026-12-05T04:46:15.046Z") as local time with its offset, to the second
/// ("2026-12-05 05:46:15 +01:00"); "–" for an empty one, the text itself when it is not such a time.
std::string local_time(const std::string& utc_iso);

}  // namespace ballbar::report
