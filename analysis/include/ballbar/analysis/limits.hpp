// SPDX-License-Identifier: MIT
// The physical ranges of the values ballbar reads from files, requests and options, and the check
// every input layer uses (docs/formats/*.md, docs/procedure.md and docs/emulator.md list them per
// input). Pure: a check returns an empty string or the reason; the caller's layer names the field,
// the file and the line, and throws its own error.
#pragma once

#include <string>
#include <string_view>

#include "ballbar/analysis/error_params.hpp"

namespace ballbar::analysis::limits {

// Positions: machine axes, sockets, pivots, offsets, circle centres. 100 m is beyond any machine tool
// and keeps every sum, product and NC word far from overflow.
inline constexpr double kPosition_mm = 100'000;
// Rotary positions (commanded axes, travel limits, offsets): 100 turns.
inline constexpr double kRotary_deg = 36'000;
// A test's rotation (plan files, `solve`): at most one turn each way.
inline constexpr double kRotation_deg = 360;
// Bar lengths (measured, nominal, a plan's bar): (0, 10 m].
inline constexpr double kLength_mm = 10'000;
// Length errors and corrections (SSM ΔV, Δl, a reading's standard deviation): the bar reads ±1 mm.
inline constexpr double kSmallLength_mm = 10;
// Temperatures of a bar, the air, a machine.
inline constexpr double kTempMin_C = -50, kTempMax_C = 150;
// Times since a session or recording started.
inline constexpr double kTime_s = 1e9;
// Feeds the procedures command (machine files, circle plan, trace headers).
inline constexpr double kFeedMin_mm_min = 0.1, kFeedMax_mm_min = 200'000;

/// Empty when `value` is finite and in [lo, hi]; otherwise the reason, such as
/// "= 1e+308 is outside [0.1, 200000] mm/min" or "is not a finite number". `unit` may be empty.
std::string check_in(double value, double lo, double hi, std::string_view unit);
/// Empty when `value` is finite, > lo and <= hi ("= 0 must be > 0 and <= 10000 mm").
std::string check_above(double value, double lo, double hi, std::string_view unit);
/// Empty when `value` is an integer in [lo, hi].
std::string check_integer_in(double value, double lo, double hi);

/// The range of an error parameter's value in its own unit (mm: ±1000, rad: ±π, mm/mm: ±0.1,
/// mm/h: ±1000, 1/K: ±0.01): finite and far beyond any real machine, so that a model "of another
/// machine" still meets `compensate`'s correction bounds (which name the line), while 1e308 is refused.
double param_limit(ParamUnit unit);
/// check_in(value, -param_limit, +param_limit, the unit's name).
std::string check_param(Param p, double value);

/// Shortest text of a double that reads back to it ("1e+308", "0.1").
std::string number_text(double value);

}  // namespace ballbar::analysis::limits
