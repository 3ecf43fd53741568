// SPDX-License-Identifier: MIT
// The point code: before each measuring dwell the NC program writes the planned point's index into the
// bar length. The tool ball moves along the bar's axis to a short sequence of *tag* lengths (bar length
// + offset) and dwells briefly at each; the bar sees a staircase of plateaus that names the point. The
// acquisition reads the staircase back (attribution.hpp) and attributes the following dwell to the
// point it names, from evidence rather than from counting dwells (docs/procedure.md).
//
// Digits are base 3; tag k is on the short side of the nominal length for even k and on the long side
// for odd k, so consecutive plateaus always differ by at least 0.9 mm and no tag is within 0.4 mm of the
// measuring length. The last digit is a check digit (a single misread digit is caught).
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <vector>

namespace ballbar::acquisition {

struct PointCodeSpec {
    double tag_dwell_s = 0.3;     ///< G4 at each tag length
    double min_offset_mm = 0.45;  ///< |offset| of digit 0
    double digit_step_mm = 0.2;   ///< offset between successive digits
    double decision_mm = 0.08;    ///< a plateau further than this from every tag level is no tag
    double min_plateau_s = 0.15;  ///< a tag plateau lasts at least this ...
    double max_plateau_s = 1.0;   ///< ... and at most this (a machine standing still is no tag)
    double max_gap_s = 0.1;       ///< a gap in the stream longer than this voids the code being read
};

/// The code's timing for an instrument of `sample_rate_hz`: at 1 kHz the defaults above; a slow
/// digital gauge (10–50 readings/s) gets tag dwells long enough for the plateau detector to see each
/// tag with several readings (at least 10 reading periods), plateau bounds scaled with them, and a
/// stream gap counted only beyond 2.5 reading periods (a polled gauge's readings come 1/rate apart).
PointCodeSpec code_for_rate(double sample_rate_hz);

/// Data digits for a plan of `point_count` points (at least 2).
int code_data_digits(std::size_t point_count);
/// The tag digits of point `index` (data digits, most significant first, then the check digit).
std::vector<int> encode_point(std::size_t index, int data_digits);
/// The point a complete digit sequence names, or nothing when its check digit does not match.
std::optional<std::size_t> decode_point(std::span<const int> digits);
/// Length offset (mm) of tag `position` (0-based) showing `digit`.
double tag_offset_mm(const PointCodeSpec& spec, int position, int digit);
/// The digit a plateau at `offset_mm` shows at tag `position`, or nothing when it is no tag level.
std::optional<int> tag_digit(const PointCodeSpec& spec, int position, double offset_mm);

}  // namespace ballbar::acquisition
