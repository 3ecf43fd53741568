// SPDX-License-Identifier: MIT
// `ballbar demo-compensate [--json] [--seed N] [--noise-um X] [--first-order]`: the compensation proof
// on the emulator (compensation_demo.hpp). `ballbar demo --compensate` calls the same function.
#include <iostream>
#include <memory>

#include "command.hpp"
#include "compensation_demo.hpp"

BALLBAR_COMMAND(demo_compensate) {
    auto opts = std::make_shared<ballbar::app::CompensationDemoOptions>();
    auto json = std::make_shared<bool>(false);
    auto* sub = root.add_subcommand(
        "demo-compensate", "identify an emulated machine's error model, compensate a test path, show the gain");
    sub->add_flag("--json", *json, "print the result as JSON");
    sub->add_option("--seed", opts->seed, "random seed (socket set-up, bar noise)");
    sub->add_option("--noise-um", opts->noise_um, "bar reading noise, um (standard deviation)")
        ->check(CLI::NonNegativeNumber);
    sub->add_option("--path-points", opts->path_points, "blocks of the test path")->check(CLI::Range(8, 1000000));
    sub->add_flag("--first-order", opts->first_order, "first-order compensation instead of the exact solution");
    sub->callback([&globals, opts, json] {
        globals.action = [opts, json]() { return ballbar::app::run_compensation_demo(*opts, std::cout, *json); };
    });
}
