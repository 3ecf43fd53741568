// SPDX-License-Identifier: MIT
// The circular test as the command line gives it (`circle plan`, `circle measure`): plane, radius,
// centre, feed, feed-in, arc and runs, turned into the test header the part program, the session and
// the analysis share (docs/circular.md, "Planning").
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "ballbar/analysis/circular.hpp"
#include "ballbar/workflow/circular_test.hpp"
#include "command.hpp"

namespace ballbar::app {

using CircleTestOptions = workflow::CircularTestInput;  ///< the options, as every front end gives them

/// Adds --radius, --centre and --feed to `cmd` (`circle plan`, `circle measure`), each checked against
/// the test header's range (docs/formats/trace.md); `feed_help` is the command's own words for --feed.
void add_circle_geometry_options(CLI::App& cmd, CircleTestOptions& test, const std::string& feed_help);

/// The test these options describe; Error (bad input) naming the option when it is not a test.
inline analysis::circular::TestSpec circle_test(const CircleTestOptions& o) {
    return workflow::circular_test_spec(o);
}

}  // namespace ballbar::app
