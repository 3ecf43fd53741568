// SPDX-License-Identifier: MIT
// `ballbar circle measure` (the circular test on an instrument, docs/procedure.md) and
// `ballbar demo --test circular` (the same procedure end to end on the emulator's continuous machine,
// each diagnostic next to the emulator's truth).
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

#include "command.hpp"

namespace ballbar::app {

/// Adds `measure` to the `circle` subcommand.
void add_circle_measure(CLI::App& circle, Globals& globals);

struct CircularDemoOptions {
    std::uint64_t seed = 1;
    bool json = false;
    std::string plane = "XY";
    double arc_deg = 0;  ///< 0: 360 in XY, the 180° partial arc in YZ and ZX
    double radius_mm = 100;
    double feed_mm_min = 1000;
    std::string faults;  ///< the emulator's "faults" object (inline JSON or a file)
    std::string report;  ///< --report PATH: the session's PDF report, written once it is stored (checked before)
};
int run_circular_demo(const CircularDemoOptions& o, const Globals& globals);

}  // namespace ballbar::app
