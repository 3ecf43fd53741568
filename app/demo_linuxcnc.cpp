// SPDX-License-Identifier: MIT
// `ballbar demo --controller linuxcnc`: parses nothing of its own beyond the demo's options, runs
// workflow::run_linuxcnc_loop and prints each location's total position error before and after
// compensation in LinuxCNC's servo loop, the gain per axis next to the second seed's (docs/linuxcnc.md).
#include "demo_linuxcnc.hpp"

#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "ballbar/analysis/effects.hpp"
#include "ballbar/report/build.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/version.hpp"
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
    lo.discover = o.discover || !o.hidden.empty();
    if (!o.hidden.empty()) {
        if (const std::string why = workflow::hidden_effect_refusal(o.hidden); !why.empty())
            throw Error(ErrorCategory::bad_input, "--hidden " + o.hidden + ": " + why);
        const ba::Effect* e = ba::find_effect(o.hidden);
        (*lo.errors)[e->param] = workflow::hidden_effect_size(e->param);
    }
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
        out["locations"].push_back(
            {{"test", l.test + 1},
             {"step", l.step},
             {"before_e_mm", vec3_json(l.before_mm)},
             {"true_before_e_mm", vec3_json(l.true_before_mm)},
             {"after_e_mm", vec3_json(l.after_mm)},
             {"third_e_mm", l.third_mm ? vec3_json(*l.third_mm) : ojson(nullptr)},
             {"machine_before_mm", vec3_json(l.machine_before_mm)},
             {"machine_after_mm", vec3_json(l.machine_after_mm)},
             {"machine_third_mm", l.machine_third_mm ? vec3_json(*l.machine_third_mm) : ojson(nullptr)}});
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
                               {"measured_after_um", r.rms_raw_after_um[i]},
                               {"third_um", r.third_session ? ojson(r.rms_third_um[i]) : ojson(nullptr)},
                               {"third_gain", r.third_session ? ojson(r.third_gain(k)) : ojson(nullptr)}});
        met = met && (r.third_session ? r.third_gain(k) : r.gain(k)) >= 10.0;  // the last measurement's
    }
    out["setup_mm"] = {{"before", vec3_json(r.setup_before_mm)},
                       {"after", vec3_json(r.setup_after_mm)},
                       {"third", r.third_session ? vec3_json(r.setup_third_mm) : ojson(nullptr)},
                       {"identified", vec3_json(r.identified_setup_mm)}};
    out["circles"] = ojson::array();
    for (const auto& c : r.circles)
        out["circles"].push_back({{"phase", c.phase},
                                  {"session", c.session},
                                  {"g_um", c.g_um},
                                  {"radial_range_um", c.radial_range_um},
                                  {"mean_radius_um", c.mean_radius_um}});
    out["goal_gain"] = 10.0;
    out["goal_met"] = met;
    out["hidden"] = o.hidden.empty() ? ojson(nullptr) : ojson(o.hidden);
    if (r.discovery_ran)
        out["discovery"] = {
            {"discovered", r.discovered},
            {"verdict", r.discovery_verdict},
            {"extended_model", r.extended_model_path.empty() ? ojson(nullptr) : ojson(r.extended_model_path)},
            {"third_session", r.third_session ? ojson(r.third_session) : ojson(nullptr)}};
    else
        out["discovery"] = nullptr;
    const std::int64_t last = r.third_session ? r.third_session : r.after_session;
    if (!o.report.empty()) {
        report::BuildOptions bo;
        bo.software_version = kVersion;
        std::vector<fileio::Protected> inputs = database_files(globals);
        inputs.push_back({o.plan, "plan file"});
        write_output(o.report, "--report", report::render_pdf_bytes(report::build_report(store, last, bo)), inputs);
        out["report"] = o.report;
    }
    if (o.json) {
        std::cout << out.dump(2) << "\n";
        return kExitOk;
    }
    std::cout << "ballbar demo --controller linuxcnc: LinuxCNC ran the programs, ballbarkins compensated\n"
              << "  before: session " << r.before_session << " (ballbarkins disabled: the nominal kinematics)\n"
              << "  model:  " << r.model_path << " (hash " << r.model_hash << ")\n";
    for (const auto& p : r.identified) std::cout << "          " << p << "\n";
    const auto um3 = [](const ba::Vec3& v) {
        char t[96];
        std::snprintf(t, sizeof t, "(%.2f, %.2f, %.2f) µm", v.x() * 1e3, v.y() * 1e3, v.z() * 1e3);
        return std::string(t);
    };
    std::cout << "  after:  session " << r.after_session << " (the model in ballbarkins)\n";
    if (r.discovery_ran) {
        std::cout << "  discovery on session " << r.before_session << ": "
                  << (r.discovered.empty() ? "nothing the model misses" : "the model misses") << "\n";
        for (const auto& d : r.discovered) std::cout << "          " << d << "\n";
        std::cout << "          what remains: " << r.discovery_verdict << "\n";
        if (r.third_session)
            std::cout << "  third:  session " << r.third_session
                      << " (the extended model in ballbarkins: " << r.extended_model_path << ")\n";
    }
    std::cout << "  the socket's set-up offset in e (best fit, table frame): before " << um3(r.setup_before_mm)
              << ", after " << um3(r.setup_after_mm);
    if (r.third_session) std::cout << ", third " << um3(r.setup_third_mm);
    std::cout << "\n  (the identification found " << um3(r.identified_setup_mm)
              << ": A_zero and C_zero cannot be told from it with one\n  socket, and no compensation removes it);"
              << " the machine's error is e less it\n\n"
              << "  location          e measured before (µm)    e measured after (µm)     machine after (µm)"
              << (r.third_session ? "     machine third (µm)" : "") << "\n";
    for (const auto& l : r.locations) {
        char line[320];
        const ba::Vec3& m = l.machine_after_mm;
        int n = std::snprintf(
            line, sizeof line, "  test %d step %d  %7.2f %7.2f %7.2f   %7.2f %7.2f %7.2f   %7.3f %7.3f %7.3f",
            l.test + 1, l.step, l.before_mm.x() * 1e3, l.before_mm.y() * 1e3, l.before_mm.z() * 1e3,
            l.after_mm.x() * 1e3, l.after_mm.y() * 1e3, l.after_mm.z() * 1e3, m.x() * 1e3, m.y() * 1e3, m.z() * 1e3);
        if (l.machine_third_mm && n > 0 && static_cast<std::size_t>(n) < sizeof line) {
            const ba::Vec3& t = *l.machine_third_mm;
            std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n), "   %7.3f %7.3f %7.3f", t.x() * 1e3,
                          t.y() * 1e3, t.z() * 1e3);
        }
        std::cout << line << "\n";
    }
    std::cout << "\n  the machine's error, RMS over the locations\n"
              << "  axis   before       after        gain   (seed: Lei & Hsu's machine)"
              << (r.third_session ? "   third        gain" : "") << "\n";
    for (int k = 0; k < 3; ++k) {
        const auto i = static_cast<std::size_t>(k);
        char line[200];
        std::snprintf(line, sizeof line, "  %c      %7.2f µm   %7.3f µm  %6.1f×   (%.1f×)", "XYZ"[k],
                      r.rms_before_um[i], r.rms_after_um[i], r.gain(k), kSeedGain[k]);
        std::cout << line;
        if (r.third_session) {
            std::snprintf(line, sizeof line, "                          %7.3f µm  %6.1f×", r.rms_third_um[i],
                          r.third_gain(k));
            std::cout << line;
        }
        std::cout << "\n";
    }
    if (!r.circles.empty()) {
        std::cout << "\n  the circular test (ISO 230-4, XY, R " << workflow::loop_plan().bar_length_mm
                  << " mm, the table at A = 30°), each through LinuxCNC after its SSM\n"
                  << "  measurement   session   G(b)        radial deviation (max − min: the set-up offset in it)\n";
        for (const auto& c : r.circles) {
            char line[200];
            std::snprintf(line, sizeof line, "  %-12s  %7lld   %7.2f µm  %7.2f µm\n", c.phase.c_str(),
                          static_cast<long long>(c.session), c.g_um, c.radial_range_um);
            std::cout << line;
        }
    }
    std::cout << "\n  goal: at least 10× on every axis" << (r.third_session ? " (the third measurement)" : "") << " — "
              << (met ? "met" : "NOT met") << "\n"
              << "  LinuxCNC's configuration, programs and logs: " << r.work_dir << "\n";
    if (!o.report.empty())
        std::cout << "  report of session " << last << " (its before/after page): " << o.report << "\n";
    return kExitOk;
}

}  // namespace ballbar::app
