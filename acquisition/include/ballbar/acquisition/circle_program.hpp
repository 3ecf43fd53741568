// SPDX-License-Identifier: MIT
// The part program of a circular test (docs/circular.md, "Plan"; the motion of docs/formats/trace.md):
// run by run, a dwell at radius R + feed-in, the radial feed-in (G1), the arcs (G3 ccw, G2 cw, centre
// words I J K, split into blocks of at most 90°) over overshoot + data arc + overshoot, the radial
// feed-out; G17/G19/G18 for XY/YZ/ZX. Written by `circle plan` and `circle measure`, run by the
// emulator's continuous machine.
#pragma once

#include <string>

#include "ballbar/analysis/circular.hpp"
#include "ballbar/analysis/nc_program.hpp"

namespace ballbar::acquisition {

/// The program text; `dwell_s` is the stand before each feed-in and at the end.
std::string circular_program(const analysis::circular::TestSpec& test, analysis::NcDialect dialect, double dwell_s);

/// Number text as the program writes it (4 decimals, trailing zeros dropped).
std::string nc_number(double v);

}  // namespace ballbar::acquisition
