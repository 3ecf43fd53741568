// SPDX-License-Identifier: MIT
// Figures on the engineer's screen: every value with its unit (µm, µrad, µm/m, arc-seconds), its
// standard uncertainty where it is known, in digits the uncertainty supports, and a flag when it
// disagrees with a known truth by more than 5σ (docs/cli.md). Human output only: --json keeps the
// code's units (mm, rad) and its keys.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/analysis/error_params.hpp"
#include "ballbar/analysis/identify.hpp"

namespace ballbar::app {

/// A unit for the screen: the factor from the code's unit and its symbol.
struct ScreenUnit {
    double factor = 1;
    std::string_view symbol;
};

/// mm → µm, rad → µrad, mm/mm → µm/m, mm/h → µm/h, 1/K → µm/m/K.
ScreenUnit screen_unit(analysis::ParamUnit unit);

/// "15.026 ± 0.016 µm": the uncertainty to two significant digits and the value to the same place;
/// without an uncertainty (`std` ≤ 0 or not finite), four significant digits and no "±".
std::string with_uncertainty(double value, double std, std::string_view unit);

/// "(-7.52, -20.71, 3.70) ± (0.05, 0.05, 0.04) µm" from mm, the decimals (2 to 4) set by two significant
/// digits of the smallest uncertainty, so an uncertainty never reads 0.00; without `std`, two decimals.
std::string vec_um(const analysis::Vec3& v_mm, const analysis::Vec3* std_mm);

/// "1 test", "6 tests": a count and its noun, plural with an s unless it is one.
std::string count_of(std::size_t n, std::string_view noun);

/// How many σ `value` lies from `truth` when that is more than kFlagSigma, else nothing.
inline constexpr double kFlagSigma = 5.0;
std::optional<double> sigma_off(double value, double std, double truth);

/// "  !! 8.9σ from the true value" (`what`: "the true value", "the tolerance") or "".
std::string sigma_flag(double value, double std, double truth, std::string_view what = "the true value");

/// An identification's summary for the terminal: convergence, residuals in µm, and each estimate in its
/// screen unit with its uncertainty and independence (replaces FitSummary::brief_report on screen).
std::string fit_report(const analysis::FitSummary& fit);

/// What the fit could not separate: the held (unobservable) parameters whose effect estimated ones
/// carry, each carrier with its change per unit of each; empty when nothing is carried.
std::string carried_note(const analysis::FitSummary& fit);

/// One estimate of a fit as "Y0A  15.026 ± 0.016 µm" (unit from the parameter; socket offsets µm).
std::string estimate_text(const analysis::ParamEstimate& e);

}  // namespace ballbar::app

namespace ballbar::app {

/// The values of one stored result, for `sessions show`: one or more lines (each without its indent
/// and newline) with units and uncertainties: SSM location errors in µm, orientation errors in
/// arc-seconds, an identification's estimates, a discovery's steps, a compensation's before/after,
/// a gauge's figures; for another kind, its top-level numbers under their own names (which carry the
/// unit: `rms_um`). `machine` is the session's machine type (which angles a test measures). Nothing for
/// a payload that is not a JSON object.
std::vector<std::string> result_lines(std::string_view kind, std::string_view payload_json,
                                      analysis::MachineType machine);

}  // namespace ballbar::app
