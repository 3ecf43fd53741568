// SPDX-License-Identifier: MIT
// `ballbar demo`: the whole guided two-step SSM procedure against the emulator, and its comparison with
// the truth. The use case is workflow::run_ssm_demo (a seed-like machine with known errors and a 0.1 µm
// bar on a pseudo-terminal, the real serial path, the session stored, every stored point checked against
// the truth); this file parses the options and prints the comparison (docs/procedure.md).
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "ballbar/acquisition/compute.hpp"
#include "ballbar/acquisition/nc_writer.hpp"
#include "ballbar/acquisition/result_codec.hpp"
#include "ballbar/acquisition/session.hpp"
#include "ballbar/report/build.hpp"
#include "ballbar/storage/compensation_codec.hpp"
#include "ballbar/version.hpp"
#include "ballbar/workflow/gauge_source.hpp"
#include "ballbar/workflow/machines.hpp"
#include "ballbar/workflow/ssm_demo.hpp"
#include "circle_measure.hpp"  // demo --test circular
#include "command.hpp"
#include "compensation_demo.hpp"
#include "demo_linuxcnc.hpp"  // demo --controller linuxcnc (issue 29)
#include "figures.hpp"
#include "files.hpp"
#include "gauge_commands.hpp"  // demo --instrument: a digital gauge (issue 14)
#include "json_out.hpp"

namespace ballbar::app {
namespace {

namespace acq = ballbar::acquisition;
namespace ba = ballbar::analysis;
using ojson = nlohmann::ordered_json;

struct DemoOptions {
    std::string machine = "TTTRR";
    std::uint64_t seed = 1;
    bool json = false;
    bool compensate = false;
    std::string report;      ///< --report PATH: write the session's PDF report
    std::string instrument;  ///< --instrument KIND: a digital gauge instead of the ballbar (gauge_demo.cpp)
    double gauge_rate_hz = 20;
    std::string faults;        ///< --faults SPEC
    std::string plan;          ///< --plan FILE: a ballbar-plan/1 file instead of the default plan
    std::string test = "ssm";  ///< --test circular: the circular test (cmd_circle_measure.cpp)
    std::string plane = "XY";
    double arc_deg = 0;
    acq::Tolerances tolerances;  ///< --location-tolerance, --angle-tolerance: the SSM's verdict
    std::string controller;      ///< --controller linuxcnc: the loop through LinuxCNC (demo_linuxcnc.cpp)
    std::string work_dir;
    std::string module;
    int error_set = 0;
    std::string hidden;     ///< --hidden EFFECT (--controller linuxcnc)
    std::string asset;      ///< --asset ID: the registry's machine, emulated
    bool discover = false;  ///< --discover (--controller linuxcnc)
};

/// The angles of one orientation entry in arcseconds ("d_alpha -46.66\""): those under `prefix` + name
/// + "_rad", the measured ones (prefix "") with ± their standard uncertainty and flagged (figures.hpp)
/// when more than 5σ from the true value.
std::string arcsec(const ojson& o, const std::string& prefix) {
    std::ostringstream os;
    os.setf(std::ios::fixed);
    os.precision(2);
    bool first = true;
    for (const char* name : {"d_alpha", "d_beta", "d_gamma"}) {
        const std::string key = prefix + name + "_rad";
        if (!o.contains(key)) continue;
        const ojson& v = o[key];
        if (v.is_null()) return "singular";
        os << (first ? "" : "  ") << name << " " << ba::rad_to_arcsec(v.get<double>()) << "\"";
        const std::string std_key = key + "_std";
        if (prefix.empty() && o.contains(std_key) && o[std_key].is_number()) {
            const double u = o[std_key].get<double>();
            os << " ± " << ba::rad_to_arcsec(u) << "\"";
            const ojson& truth = o[std::string("true_") + name + "_rad"];
            if (truth.is_number()) os << sigma_flag(v.get<double>(), u, truth.get<double>());
        }
        first = false;
    }
    return os.str();
}

/// The largest |measured − true| / std over a location's components, or 0 without uncertainties.
double location_sigma(const ojson& l) {
    double worst = 0;
    for (std::size_t a = 0; a < 3; ++a) {
        const double s = l["e_mm_std"][a].get<double>();
        if (s > 0) worst = std::max(worst, std::abs(l["e_mm"][a].get<double>() - l["true_e_mm"][a].get<double>()) / s);
    }
    return worst;
}

int run_demo(const DemoOptions& o, const Globals& globals) {
    std::vector<fileio::Protected> inputs = database_files(globals);
    inputs.push_back({o.plan, "plan file"});
    inputs.push_back({o.faults, "faults file"});
    if (!o.report.empty()) {
        try {
            fileio::check_output(o.report, "--report", inputs);  // before the demo runs
        } catch (const fileio::FileError& e) {
            throw as_error(e);
        }
    }
    if (!o.asset.empty() && (o.controller == "linuxcnc" || o.test == "circular" ||
                             (!o.instrument.empty() && o.instrument != "ballbar") || o.compensate))
        throw Error(ErrorCategory::bad_input,
                    "--asset runs the SSM demo on the registered machine; not with --controller, --test circular, "
                    "--instrument or --compensate");
    if (o.controller == "linuxcnc")
        return run_linuxcnc_demo(
            {o.seed, o.json, o.work_dir, o.module, o.error_set, o.plan, o.hidden, o.discover, o.report}, globals);
    if (o.test == "circular")
        return run_circular_demo({o.seed, o.json, o.plane, o.arc_deg, 100.0, 1000.0, o.faults, o.report}, globals);
    if (!o.instrument.empty() && o.instrument != "ballbar")
        return run_gauge_demo({o.instrument, o.machine, o.seed, o.gauge_rate_hz, o.json}, resolve_db_path(globals));
    // A killed demo loses at most its last batch; the demo does not need an fsync per commit.
    storage::StoreOptions so;
    so.sync_full = false;
    std::optional<storage::Store> registry;
    workflow::SsmDemoOptions demo;
    if (!o.asset.empty()) {
        registry.emplace(existing_db_path(globals), so);
        demo.registered = workflow::registered_machine_file(*registry, o.asset);
        demo.machine_asset = o.asset;
    }
    const auto type =
        demo.registered ? std::optional(demo.registered->geometry.type) : ba::parse_machine_type(o.machine);
    if (!type) throw Error(ErrorCategory::bad_input, "--machine must be RRTTT, TTTRR or RTTTR");
    demo.machine = *type;
    demo.seed = o.seed;
    demo.tolerances = o.tolerances;
    demo.notes = "ballbar demo --machine " + o.machine + " --seed " + std::to_string(o.seed);
    if (!o.plan.empty()) {
        try {
            demo.plan = acq::parse_plan_file(read_file(o.plan, "plan file"), *type);
            // Planned (travel, conditioning, rotations) before anything is stored: a refused plan leaves
            // no database behind.
            (void)acq::make_plan(acq::seed_machine(*type), *demo.plan);
        } catch (const acq::PlanError& e) {
            throw Error(ErrorCategory::bad_input, o.plan + ": " + e.what());
        }
        demo.plan->answers.on_point_failure = acq::PointFailureAction::Retry;  // the demo's operator never gives up
    }
    if (!o.faults.empty()) demo.faults = parse_faults_option(o.faults);

    if (!registry) registry.emplace(resolve_db_path(globals), so);
    storage::Store& store = *registry;

    const bool show = !o.json && ::isatty(STDERR_FILENO);  // the running count, on a terminal
    std::size_t last_done = static_cast<std::size_t>(-1);
    workflow::SsmDemoEvents events;
    events.started = [&](std::int64_t, const acq::Plan& plan, const std::string& pty) {
        if (!o.json)
            std::cout << "ballbar demo: " << ba::to_string(plan.machine.geometry.type) << " ("
                      << plan.machine.geometry.name << "), " << plan.test_count() << " two-step tests, "
                      << plan.points.size() << " points; emulator on " << pty << "\n";
    };
    events.progress = [&](const acq::Progress& p) {
        if (!show || p.done == last_done) return;
        last_done = p.done;
        std::fprintf(stderr, "\r  captured %zu/%zu points", p.done, p.total);
        std::fflush(stderr);
    };
    // What the procedure waits for, and how long: a demo on a silent link must not be silent itself.
    if (!o.json)
        events.message = [&](std::string_view text) {
            std::fprintf(stderr, "%s  %.*s\n", show ? "\r" : "", static_cast<int>(text.size()), text.data());
        };
    struct EndLine {  // the running count's line ends however the demo does
        bool show;
        ~EndLine() {
            if (show) std::fputc('\n', stderr);
        }
    };
    workflow::SsmDemoResult run;
    {
        const EndLine end{show};
        run = workflow::run_ssm_demo(store, demo, events);
    }
    const std::int64_t id = run.session_id;
    const acq::Plan& plan = run.plan;
    const acq::SessionSummary& sum = run.summary;
    const workflow::TruthCheck& tc = run.check;

    // Compare with the truth.
    ojson out;
    out["session"] = id;
    out["machine"] = std::string(ba::to_string(plan.machine.geometry.type));
    out["locations"] = ojson::array();
    out["orientation"] = ojson::array();
    for (const auto& [l, tr] : run.locations) {
        // ΔV as `measure` prints it (the seed's sign: the moving element's error), beside e.
        const double sign = acq::dv_sign(plan, l.test);
        out["locations"].push_back({{"test", l.test + 1},
                                    {"step", l.step},
                                    {"e_mm", vec3_json(l.ssm.exact_mm)},
                                    {"e_mm_std", vec3_json(l.ssm.std_mm)},
                                    {"true_e_mm", vec3_json(tr)},
                                    {"dV_mm", vec3_json(l.dV_mm)},
                                    {"true_dV_mm", vec3_json(sign * tr)}});
    }
    for (const auto& r : sum.tests) {
        const auto& t = run.truth[static_cast<std::size_t>(r.test)];
        ojson o_j = {{"test", r.test + 1}, {"kind", std::string(acq::to_string(r.kind))}};
        put_angles(o_j, "", "", r.orientation.exact, *type, r.kind);
        put_angles(o_j, "", "_std", r.std_rad, *type, r.kind);
        put_angles(o_j, "true_", "", t.result.orientation.exact, *type, r.kind);
        put_angles(o_j, "first_order_", "", r.orientation.first_order, *type, r.kind);
        put_angles(o_j, "true_first_order_", "", t.result.orientation.first_order, *type, r.kind);
        out["orientation"].push_back(std::move(o_j));
    }
    const acq::SsmVerdict verdict = acq::judge_ssm(*type, plan.machine.tolerances, plan.spec.tests, sum.tests);
    out["verdict"] = verdict_json(verdict);
    out["samples"] = sum.samples;
    out["programs"] = sum.programs;
    out["void_dwells"] = sum.void_dwells;
    out["pauses"] = sum.pauses;
    out["truth_check"] = {{"points", tc.points},
                          {"wrong_pose", tc.wrong_pose},
                          {"stored_twice", tc.stored_twice},
                          {"samples_stored", tc.samples_stored},
                          {"dropped_frames", run.dropped_frames},
                          {"replayed_frames", run.replayed_frames},
                          {"corrupted_bytes", run.corrupted_bytes}};

    int code = kExitOk;
    std::string compensation_text;  // printed after the session's tables
    if (o.compensate) {
        workflow::CompensationDemoOptions co;
        co.seed = o.seed;
        const workflow::CompensationDemo cd = workflow::run_compensation_demo(co);
        if (o.json) {
            out["compensation"] = compensation_demo_json(cd, co);
            // Issue 6's figures at the top level too: the improvement, the RMS before and after, the estimates.
            for (const char* key : {"improvement_ratio", "rms_before_um", "rms_after_um", "identified"})
                out[key] = out["compensation"][key];
        } else {
            compensation_text = compensation_demo_text(cd, co.noise_um);
        }
        if (!cd.fit.converged) code = kExitFailure;
        // Stored with the demo session, so its report shows the before/after -- only with a TTTRR
        // session: the proof runs on an emulated TTTRR machine.
        if (*type == ba::MachineType::TTTRR) workflow::store_compensation_demo(store, id, cd, o.seed);
    }
    if (!o.report.empty()) {
        report::BuildOptions bo;
        bo.software_version = kVersion;  // "ballbar 0.x.y" on the set-up table, as `ballbar report` writes
        write_output(o.report, "--report", report::render_pdf_bytes(report::build_report(store, id, bo)), inputs);
        out["report"] = o.report;
    }
    if (o.json) {
        std::cout << out.dump() << std::endl;
    } else {
        std::printf(
            "\nLocation errors ΔV, µm (as `measure` prints them: the moving element's error, ΔV = ±e with\n"
            "e = (b - s)actual - (b - s)nominal; SSM exact, %s layout):\n",
            std::string(ba::to_string(plan.spec.layout)).c_str());
        std::printf(
            "  test step   measured (x, y, z)              true (x, y, z)                  |diff|   (!! more than "
            "5σ from the truth)\n");
        for (const auto& l : out["locations"]) {
            const auto& m = l["dV_mm"];
            const auto& t = l["true_dV_mm"];
            const double d =
                std::hypot(m[0].get<double>() - t[0].get<double>(), m[1].get<double>() - t[1].get<double>(),
                           m[2].get<double>() - t[2].get<double>());
            const double sigma = location_sigma(l);
            char flag[48] = "";
            if (sigma > kFlagSigma) std::snprintf(flag, sizeof flag, "   !! %.1fσ", sigma);
            std::printf("  %4d %4d   %8.3f %8.3f %8.3f    %8.3f %8.3f %8.3f    %6.3f%s\n", l["test"].get<int>(),
                        l["step"].get<int>(), 1e3 * m[0].get<double>(), 1e3 * m[1].get<double>(),
                        1e3 * m[2].get<double>(), 1e3 * t[0].get<double>(), 1e3 * t[1].get<double>(),
                        1e3 * t[2].get<double>(), 1e3 * d, flag);
        }
        std::printf("\nOrientation errors (exact model), arc-seconds:\n");
        for (const auto& t : out["orientation"])
            std::printf("  test %d (%s): measured %s | true %s\n", t["test"].get<int>(),
                        t["kind"].get<std::string>().c_str(), arcsec(t, "").c_str(), arcsec(t, "true_").c_str());
        if (verdict.judged()) std::printf("\n%s\n", verdict.summary().c_str());
        std::printf("\nSession %lld stored in %s (%zu samples).\n", static_cast<long long>(id), store.path().c_str(),
                    sum.samples);
        std::printf(
            "Checked against the emulator's truth: %zu points, each at its planned pose and socket; no "
            "sample stored twice.\n",
            tc.points);
        if (!o.report.empty()) std::printf("Report written to %s.\n", o.report.c_str());
    }
    if (!compensation_text.empty()) std::cout << "\n" << compensation_text << std::flush;
    return code;
}

}  // namespace

BALLBAR_COMMAND(demo) {
    auto* sub =
        root.add_subcommand("demo", "Run the guided two-step SSM procedure on the emulator and compare with the truth");
    auto o = std::make_shared<DemoOptions>();
    sub->add_option("--machine", o->machine, "Machine type: RRTTT, TTTRR or RTTTR")
        ->check(CLI::IsMember({"RRTTT", "TTTRR", "RTTTR"}));
    sub->add_option("--seed", o->seed, "Seed of the emulator's noise (same seed, same session)");
    sub->add_flag("--json", o->json, "Print the comparison as JSON");
    sub->add_option("--report", o->report, "Also write the session's PDF report to this file");
    sub->add_flag("--compensate", o->compensate, "Then identify the errors and show the compensation");
    sub->add_option("--instrument", o->instrument, "ballbar (default) or a digital gauge on the bar")
        ->check(CLI::IsMember({"ballbar", "sylvac", "mitutoyo-itn", "digimatic", "modbus"}));
    sub->add_option("--rate", o->gauge_rate_hz, "The gauge's readings per second (--instrument)")
        ->check(in_range(5, 1000, "readings/s"));
    sub->add_option("--plan", o->plan, "Plan file (ballbar-plan/1) instead of the default four tests at one socket");
    sub->add_option("--faults", o->faults,
                    "Emulator faults (its \"faults\" object, docs/emulator.md): inline JSON or a file");
    sub->add_option("--test", o->test, "ssm (default: the two-step SSM) or circular (ISO 230-4)")
        ->check(CLI::IsMember({"ssm", "circular"}));
    sub->add_option("--plane", o->plane, "--test circular: XY, YZ or ZX")->check(CLI::IsMember({"XY", "YZ", "ZX"}));
    sub->add_option("--arc", o->arc_deg, "--test circular: data arc, degrees (default 360 in XY, 180 in YZ and ZX)")
        ->check(in_range(30, 360, "°"));
    sub->add_option("--controller", o->controller,
                    "linuxcnc: the whole loop through LinuxCNC's simulator (measure, identify, compensate in "
                    "ballbarkins, measure again; docs/linuxcnc.md)")
        ->check(CLI::IsMember({"linuxcnc"}));
    sub->add_option("--work-dir", o->work_dir,
                    "--controller linuxcnc: a new directory for LinuxCNC's configuration, programs, model and logs");
    sub->add_option("--module", o->module,
                    "--controller linuxcnc: a build tree's ballbarkins.so (linked into LinuxCNC's modules; root)");
    sub->add_option("--error-set", o->error_set,
                    "--controller linuxcnc: 0 (default) the demo machine's errors, K > 0 random ones of that size")
        ->check(CLI::Range(0, 1000000));
    sub->add_flag("--discover", o->discover,
                  "--controller linuxcnc: then the discovery workflow on the first session; what it names goes "
                  "into ballbarkins with the model and the SSM is measured a third time");
    sub->add_option("--asset", o->asset,
                    "the SSM demo on a registered machine (ballbar machines add): its geometry emulated, the session "
                    "stored under its asset id");
    sub->add_option("--hidden", o->hidden,
                    "--controller linuxcnc: an effect outside the model in the emulated machine, at a typical "
                    "size (an id of docs/discovery.md's library, e.g. squareness_XY); implies --discover");
    sub->add_option("--location-tolerance", o->tolerances.location_um,
                    "SSM: |ΔV| allowed at each location, µm: a PASS/FAIL verdict (stored with the session)")
        ->check(in_range(0, 10000, "µm", true));
    sub->add_option("--angle-tolerance", o->tolerances.angle_arcsec,
                    "SSM: |Δα|, |Δβ|, |Δγ| allowed, arcsec: a PASS/FAIL verdict (stored with the session)")
        ->check(in_range(0, 36000, "arcsec", true));
    sub->callback([o, &globals] { globals.action = [o, &globals] { return run_demo(*o, globals); }; });
}

}  // namespace ballbar::app
