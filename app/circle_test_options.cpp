// SPDX-License-Identifier: MIT
#include "circle_test_options.hpp"

#include "command.hpp"

namespace ballbar::app {

void add_circle_geometry_options(CLI::App& cmd, CircleTestOptions& test, const std::string& feed_help) {
    cmd.add_option("--radius", test.radius_mm, "programmed radius = bar length, mm")
        ->check(in_range(0, 10000, "mm", true))
        ->capture_default_str();
    cmd.add_option("--centre", test.centre_mm, "circle centre X Y Z, mm (where the socket sits)")
        ->expected(3)
        ->check(in_range(-100000, 100000, "mm"));
    cmd.add_option("--feed", test.feed_mm_min, feed_help)
        ->check(in_range(0.1, 200000, "mm/min"))
        ->capture_default_str();
}

}  // namespace ballbar::app
