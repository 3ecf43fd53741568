// SPDX-License-Identifier: MIT
// `ballbar demo --controller linuxcnc`: parses nothing of its own beyond the demo's options, runs
// workflow::run_linuxcnc_loop and prints each location's total position error before and after
// compensation in LinuxCNC's servo loop, the gain per axis next to the second seed's (docs/linuxcnc.md).
#include "demo_linuxcnc.hpp"

#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "ballbar/storage/store.hpp"
#include "ballbar/workflow/linuxcnc_loop.hpp"
#include "figures.hpp"
#include "files.hpp"
#include "json_out.hpp"

namespace ballbar::app {

namespace {
namespace ba = ballbar::analysis;
using ojson = nlohmann::ordered_json;
// Lei & Hsu's measured improvement on their machine, X Y Z (the second seed).
constexpr double kSeedGain[3] = {7.8, 3.2, 8.2};
}  // namespace

int run_linuxcnc_demo(const LinuxcncDemoOptions& o, const Globals& globals) {
    storage::StoreOptions so;
    so.sync_full = false;
    storage::Store store(resolve_db_path(globals), so);
    workflow::LinuxcncLoopOptions lo;
    lo.seed = o.seed;
    lo.work_dir = o.work_dir;
    lo.module_path = o.module;
    lo.errors = workflow::loop_errors(o.error_set);
    if (!o.plan.empty()) {
        try {
            lo.plan = acquisition::parse_plan_file(read_file(o.plan, "plan file"), analysis::MachineType::TTTRR);
            (void)acquisition::make_plan(workflow::loop_machine(), *lo.plan);  // refused before LinuxCNC starts
        } catch (const acquisition::PlanError& e) {
            throw Error(ErrorCategory::bad_input, o.plan + ": " + e.what());
        }
        lo.plan->answers.on_point_failure = acquisition::PointFailureAction::Retry;
    }
    workflow::LinuxcncLoopEvents events;
    events.message = [&](std::string_view text) {
        if (!o.json) std::fprintf(stderr, "  %.*s\n", static_cast<int>(text.size()), text.data());
    };
    const workflow::LinuxcncLoopResult r = workflow::run_linuxcnc_loop(store, lo, events);

    ojson out;
    out["work_dir"] = r.work_dir;
    out["before_session"] = r.before_session;
    out["after_session"] = r.after_session;
    out["model"] = r.model_path;
    out["model_hash"] = r.model_hash;
    out["identified"] = r.identified;
    out["servo_cycles"] = r.servo_cycles;
    out["locations"] = ojson::array();
    for (const auto& l : r.locations)
        out["locations"].push_back({{"test", l.test + 1},
                                    {"step", l.step},
                                    {"before_e_mm", vec3_json(l.before_mm)},
                                    {"true_before_e_mm", vec3_json(l.true_before_mm)},
                                    {"after_e_mm", vec3_json(l.after_mm)},
                                    {"setup_mm", vec3_json(l.setup_mm)}});
    out["axes"] = ojson::array();
    bool met = true;
    for (int k = 0; k < 3; ++k) {
        const auto i = static_cast<std::size_t>(k);
        out["axes"].push_back({{"axis", std::string(1, "XYZ"[k])},
                               {"before_um", r.rms_before_um[i]},
                               {"after_um", r.rms_after_um[i]},
                               {"gain", r.gain(k)},
                               {"seed_gain", kSeedGain[k]},
                               {"measured_before_um", r.rms_raw_before_um[i]},
                               {"measured_after_um", r.rms_raw_after_um[i]}});
        met = met && r.gain(k) >= 10.0;
    }
    out["setup_offset_mm"] = vec3_json(r.setup_offset_mm);
    out["goal_gain"] = 10.0;
    out["goal_met"] = met;
    if (o.json) {
        std::cout << out.dump(2) << "\n";
        return kExitOk;
    }
    std::cout << "ballbar demo --controller linuxcnc: LinuxCNC ran the programs, ballbarkins compensated\n"
              << "  before: session " << r.before_session << " (ballbarkins disabled: the nominal kinematics)\n"
              << "  model:  " << r.model_path << " (hash " << r.model_hash << ")\n";
    for (const auto& p : r.identified) std::cout << "          " << p << "\n";
    char setup[160];
    std::snprintf(setup, sizeof setup, "(%.2f, %.2f, %.2f) µm", r.setup_offset_mm.x() * 1e3,
                  r.setup_offset_mm.y() * 1e3, r.setup_offset_mm.z() * 1e3);
    std::cout
        << "  after:  session " << r.after_session << " (the model in ballbarkins)\n"
        << "  the socket's set-up offset the identification found: " << setup
        << " (A_zero and C_zero\n  cannot be told from it with one socket); the machine's error is e without it\n\n"
        << "  location          e measured before (µm)    e measured after (µm)     machine after (µm)\n";
    for (const auto& l : r.locations) {
        char line[240];
        const ba::Vec3 m = l.machine_after_mm();
        std::snprintf(line, sizeof line,
                      "  test %d step %d  %7.2f %7.2f %7.2f   %7.2f %7.2f %7.2f   %7.3f %7.3f %7.3f\n", l.test + 1,
                      l.step, l.before_mm.x() * 1e3, l.before_mm.y() * 1e3, l.before_mm.z() * 1e3, l.after_mm.x() * 1e3,
                      l.after_mm.y() * 1e3, l.after_mm.z() * 1e3, m.x() * 1e3, m.y() * 1e3, m.z() * 1e3);
        std::cout << line;
    }
    std::cout << "\n  the machine's error, RMS over the locations\n"
              << "  axis   before       after        gain   (seed: Lei & Hsu's machine)\n";
    for (int k = 0; k < 3; ++k) {
        const auto i = static_cast<std::size_t>(k);
        char line[160];
        std::snprintf(line, sizeof line, "  %c      %7.2f µm   %7.3f µm  %6.1f×   (%.1f×)\n", "XYZ"[k],
                      r.rms_before_um[i], r.rms_after_um[i], r.gain(k), kSeedGain[k]);
        std::cout << line;
    }
    std::cout << "\n  goal: at least 10× on every axis — " << (met ? "met" : "NOT met") << "\n"
              << "  LinuxCNC's configuration, programs and logs: " << r.work_dir << "\n";
    return kExitOk;
}

}  // namespace ballbar::app
