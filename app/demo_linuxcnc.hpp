// SPDX-License-Identifier: MIT
// `ballbar demo --controller linuxcnc`: the whole loop on LinuxCNC's simulator (workflow/linuxcnc_loop.hpp).
#pragma once

#include <cstdint>
#include <string>

#include "command.hpp"

namespace ballbar::app {

struct LinuxcncDemoOptions {
    std::uint64_t seed = 1;
    bool json = false;
    std::string work_dir;   ///< --work-dir: a new directory for LinuxCNC's configuration, programs, model, logs
    std::string module;     ///< --module: a build tree's ballbarkins.so (linked into LinuxCNC's module directory)
    int error_set = 0;      ///< --error-set: the emulated machine's errors (workflow::loop_errors)
    std::string plan;       ///< --plan: a ballbar-plan/1 file instead of workflow::loop_plan()
    std::string hidden;     ///< --hidden: an effect outside the model in the emulated machine (implies discover)
    bool discover = false;  ///< --discover: the discovery workflow, the extended model, a third measurement
    std::string report;     ///< --report: the last session's PDF report (its before/after page)
};
int run_linuxcnc_demo(const LinuxcncDemoOptions& o, const Globals& globals);

}  // namespace ballbar::app
