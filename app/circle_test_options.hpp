// SPDX-License-Identifier: MIT
// The circular test as the command line gives it (`circle plan`, `circle measure`): plane, radius,
// centre, feed, feed-in, arc and runs, turned into the test header the part program, the session and
// the analysis share (docs/circular.md, "Planning").
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "ballbar/analysis/circular.hpp"
#include "command.hpp"

namespace ballbar::app {

struct CircleTestOptions {
    std::string plane = "XY";
    double radius_mm = 100.0;
    std::vector<double> centre_mm{0.0, 0.0, 0.0};
    double feed_mm_min = 1000.0;
    double feed_in_mm = 1.5;
    double arc_deg = 360.0;
    std::optional<double> overshoot_deg;  ///< default: 45 for a full circle, 20 for a partial arc
    std::optional<double> start_deg;      ///< default: 0 (full) or −overshoot (partial)
    std::string directions = "both";      ///< both (ccw, then cw from where it ended), ccw or cw
};

/// Adds --radius, --centre and --feed to `cmd` (`circle plan`, `circle measure`), each checked against
/// the test header's range (docs/formats/trace.md); `feed_help` is the command's own words for --feed.
void add_circle_geometry_options(CLI::App& cmd, CircleTestOptions& test, const std::string& feed_help);

/// The test these options describe; Error (bad input) naming the option when it is not a test.
analysis::circular::TestSpec circle_test(const CircleTestOptions& o);

}  // namespace ballbar::app
