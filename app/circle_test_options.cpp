// SPDX-License-Identifier: MIT
#include "circle_test_options.hpp"

#include "command.hpp"

namespace ballbar::app {

namespace circ = analysis::circular;

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

circ::TestSpec circle_test(const CircleTestOptions& o) {
    circ::TestSpec t;
    const auto plane = circ::parse_plane(o.plane);
    if (!plane) throw Error(ErrorCategory::bad_input, "--plane must be XY, YZ or ZX");
    t.plane = *plane;
    t.radius_mm = o.radius_mm;
    if (o.centre_mm.size() != 3) throw Error(ErrorCategory::bad_input, "--centre needs three numbers X Y Z");
    t.centre_mm = {o.centre_mm[0], o.centre_mm[1], o.centre_mm[2]};
    t.feed_mm_min = o.feed_mm_min;
    t.feed_in_mm = o.feed_in_mm;
    if (o.directions != "both" && o.directions != "ccw" && o.directions != "cw")
        throw Error(ErrorCategory::bad_input, "--directions must be both, ccw or cw");
    const bool full = o.arc_deg >= 360.0;
    const double over = o.overshoot_deg ? *o.overshoot_deg : full ? 45.0 : 20.0;  // (checked by validate())
    const double start = o.start_deg ? *o.start_deg : full ? 0.0 : -over;
    const double end = start + 2.0 * over + o.arc_deg;
    if (o.directions == "both" || o.directions == "ccw")
        t.runs.push_back({circ::Direction::Ccw, start, over, o.arc_deg});
    if (o.directions == "both") t.runs.push_back({circ::Direction::Cw, end, over, o.arc_deg});
    if (o.directions == "cw") t.runs.push_back({circ::Direction::Cw, start, over, o.arc_deg});
    if (const auto bad = t.validate(); !bad.empty()) throw Error(ErrorCategory::bad_input, bad);
    return t;
}

}  // namespace ballbar::app
