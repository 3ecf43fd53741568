// SPDX-License-Identifier: MIT
// `ballbar demo`: the whole guided two-step SSM procedure against the emulator. The emulator (a
// seed-like machine with known errors and a 0.1 µm bar) is served on a pseudo-terminal by a thread of
// this process, on simulated time as fast as the host reads; the procedure talks to it through the real
// path (serial transport on the pty → protocol → driver), stores the session, and prints the measured
// total position and orientation errors next to the emulator's true values (docs/procedure.md).
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
#include "ballbar/device/emulator_host.hpp"
#include "ballbar/device/uri.hpp"
#include "ballbar/workflow/gauge_source.hpp"
#include "ballbar/workflow/pty_emulator.hpp"
#include "ballbar/workflow/session_io.hpp"
#include "circle_measure.hpp"  // demo --test circular
#include "command.hpp"
#include "figures.hpp"
#include "files.hpp"
#include "gauge_commands.hpp"  // demo --instrument: a digital gauge (issue 14)
#if __has_include("ballbar/report/build.hpp")
#include "ballbar/report/build.hpp"
#define BALLBAR_HAVE_REPORT 1
#endif
#if __has_include("compensation_demo.hpp")
#include "compensation_demo.hpp"
#define BALLBAR_HAVE_COMPENSATION_DEMO 1
#endif

namespace ballbar::app {
namespace {

namespace acq = ballbar::acquisition;
namespace ba = ballbar::analysis;
using json = nlohmann::ordered_json;

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
};

/// Answers every question like the plan and drives the emulator's machine as its operator would: runs
/// each program it is told to start (late, at a feed override, when the faults say so), presses cycle
/// start at every program stop and moves the socket when the stop says so.
class DemoOperator : public acq::ScriptedOperator {
  public:
    /// `show_progress`: the running count on a terminal; `talk`: the procedure's messages on stderr (what
    /// it waits for, and how long: a demo on a silent link must not be silent itself).
    DemoOperator(const acq::Plan& plan, device::SimulatedMachine& machine, bool show_progress, bool talk,
                 const device::FaultConfig& faults)
        : acq::ScriptedOperator(plan.spec.answers),
          machine_(machine),
          show_(show_progress),
          talk_(talk),
          start_delay_s_(faults.start_delay_s),
          feed_override_(faults.feed_override),
          answer_delay_s_(faults.answer_delay_s) {}
    void run_program(const ba::NcProgram& program, std::span<const std::size_t>, bool) override {
        machine_.stop(0);  // stops wherever it is now
        machine_.set_feed_override(feed_override_);
        if (start_delay_s_ > 0) machine_.dwell(start_delay_s_);
        machine_.run_program(program);
        ++programs;
    }
    void program_stop(const acq::ProgramStop& stop) override {
        if (stop.socket_mm) machine_.set_socket_mm(*stop.socket_mm);
        if (answer_delay_s_ > 0) machine_.dwell(answer_delay_s_);  // stands at the stop, then cycle start
        machine_.cycle_start(0);                                   // the rest runs once the machine stands at the stop
    }
    void progress(const acq::Progress& p) override {
        if (!show_ || p.done == last_done_) return;
        last_done_ = p.done;
        std::fprintf(stderr, "\r  captured %zu/%zu points", p.done, p.total);
        std::fflush(stderr);
    }
    void message(std::string_view text) override {
        if (talk_) std::fprintf(stderr, "%s  %.*s\n", show_ ? "\r" : "", static_cast<int>(text.size()), text.data());
    }
    ~DemoOperator() override {
        if (show_) std::fputc('\n', stderr);
    }
    int programs = 0;

  private:
    device::SimulatedMachine& machine_;
    bool show_, talk_;
    double start_delay_s_, feed_override_, answer_delay_s_;
    std::size_t last_done_ = static_cast<std::size_t>(-1);
};

/// What the emulator's truth says of a stored session: each stored point's window of samples is checked
/// against where the emulated machine truly stood at each sample's time (pose and socket), and the
/// stored stream for samples stored twice (the same device time).
struct TruthCheck {
    std::size_t points = 0;
    std::size_t wrong_pose = 0;    ///< points with a window sample away from the point's planned pose
    std::size_t stored_twice = 0;  ///< stored samples whose device time another stored sample has
    std::size_t samples_stored = 0;
    std::string first_wrong;  ///< the first wrong point, for the message
};

TruthCheck check_against_truth(storage::Store& store, std::int64_t id, const device::Emulator& emu) {
    TruthCheck c;
    const device::SimulatedMachine& m = emu.machine();
    const auto samples = store.samples(id);
    c.samples_stored = samples.size();
    std::vector<std::uint64_t> times;
    times.reserve(samples.size());
    for (const auto& s : samples) times.push_back(s.device_time_us);
    std::sort(times.begin(), times.end());
    c.stored_twice = static_cast<std::size_t>(times.end() - std::unique(times.begin(), times.end()));
    for (const auto& p : store.points(id)) {
        ++c.points;
        if (!p.first_seq || !p.last_seq || *p.last_seq < *p.first_seq || *p.last_seq >= samples.size()) {
            ++c.wrong_pose;
            continue;
        }
        const ba::Pose& want = p.reading.pose;
        bool ok = true;
        std::string why;
        for (std::uint64_t q = *p.first_seq; q <= *p.last_seq && ok; ++q) {
            const double t_s = static_cast<double>(samples[static_cast<std::size_t>(q)].device_time_us) * 1e-6;
            const auto t = m.truth_at(t_s);
            ok = t && (t->pose.linear_mm() - want.linear_mm()).norm() < 1e-4 &&
                 std::abs(t->pose.A_rad - want.A_rad) < 1e-6 && std::abs(t->pose.B_rad - want.B_rad) < 1e-6 &&
                 std::abs(t->pose.C_rad - want.C_rad) < 1e-6 && (t->socket_mm - p.reading.socket_mm).norm() < 1e-6;
            if (!ok) {
                std::ostringstream os;
                os << "sample " << q << " at " << t_s << " s: ";
                if (t)
                    os << "the machine at X" << t->pose.X_mm << " Y" << t->pose.Y_mm << " Z" << t->pose.Z_mm
                       << ", socket " << t->socket_mm.transpose() << "; planned X" << want.X_mm << " Y" << want.Y_mm
                       << " Z" << want.Z_mm << ", socket " << p.reading.socket_mm.transpose();
                else
                    os << "a time the machine has not reached";
                why = os.str();
            }
        }
        if (!ok) {
            ++c.wrong_pose;
            if (c.first_wrong.empty())
                c.first_wrong = "location " + std::to_string(p.reading.location) + " point " +
                                std::to_string(p.reading.point) + ", " + why;
        }
    }
    return c;
}

/// --faults SPEC: the emulator's "faults" object, inline JSON or a file holding it.
device::FaultConfig parse_faults(const std::string& spec) {
    std::string text = spec;
    const auto first = spec.find_first_not_of(" \t\n");
    if (first == std::string::npos || spec[first] != '{') text = read_file(spec, "faults file");
    try {
        return device::parse_emulator_config("{\"faults\": " + text + "}").faults;
    } catch (const std::invalid_argument& e) {
        throw Error(ErrorCategory::bad_input, std::string("--faults: ") + e.what());
    }
}

json angles_json(const std::optional<ba::OrientationErrors>& e, ba::MachineType type, acq::TestKind kind) {
    if (!e) return nullptr;
    json j = json::object();
    const ba::MeasuredAngles angles = acq::measured_angles(type, kind);
    if (angles.alpha) j["d_alpha"] = e->d_alpha_rad;
    if (angles.beta) j["d_beta"] = e->d_beta_rad;
    if (angles.gamma) j["d_gamma"] = e->d_gamma_rad;
    return j;
}

/// `angles` in arcseconds ("d_alpha -46.66\""), each with ± its standard uncertainty from `std` when
/// given, and flagged (figures.hpp) when more than 5σ from `truth` when given.
std::string arcsec(const json& angles, const json& std = nullptr, const json& truth = nullptr) {
    std::ostringstream os;
    os.setf(std::ios::fixed);
    os.precision(2);
    if (angles.is_null()) return "singular";
    bool first = true;
    for (const auto& [k, v] : angles.items()) {
        os << (first ? "" : "  ") << k << " " << ba::rad_to_arcsec(v.get<double>()) << "\"";
        if (std.is_object() && std.contains(k)) {
            os << " ± " << ba::rad_to_arcsec(std[k].get<double>()) << "\"";
            if (truth.is_object() && truth.contains(k))
                os << sigma_flag(v.get<double>(), std[k].get<double>(), truth[k].get<double>());
        }
        first = false;
    }
    return os.str();
}

/// The largest |measured − true| / std over a location's components, or 0 without uncertainties.
double location_sigma(const json& l) {
    double worst = 0;
    for (std::size_t a = 0; a < 3; ++a) {
        const double s = l["std_mm"][a].get<double>();
        if (s > 0)
            worst = std::max(worst, std::abs(l["measured_mm"][a].get<double>() - l["true_mm"][a].get<double>()) / s);
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
    if (o.test == "circular")
        return run_circular_demo({o.seed, o.json, o.plane, o.arc_deg, 100.0, 1000.0, o.faults}, globals);
    if (!o.instrument.empty() && o.instrument != "ballbar")
        return run_gauge_demo({o.instrument, o.machine, o.seed, o.gauge_rate_hz, o.json}, resolve_db_path(globals));
    const auto type = ba::parse_machine_type(o.machine);
    if (!type) throw Error(ErrorCategory::bad_input, "--machine must be RRTTT, TTTRR or RTTTR");
    const acq::MachineFile machine = acq::seed_machine(*type);
    acq::PlanSpec spec = acq::default_plan(machine);
    if (!o.plan.empty()) {
        try {
            spec = acq::parse_plan_file(read_file(o.plan, "plan file"), machine.geometry.type);
        } catch (const acq::PlanError& e) {
            throw Error(ErrorCategory::bad_input, o.plan + ": " + e.what());
        }
        spec.answers.on_point_failure = acq::PointFailureAction::Retry;  // the demo's operator never gives up
    }
    spec.answers.operator_name = "demo";
    const acq::Plan plan = acq::make_plan(machine, spec);

    device::EmulatorConfig cfg;
    cfg.seed = o.seed;
    cfg.instrument.calibrated_length_mm = spec.bar_length_mm;
    cfg.instrument.noise_um = 0.1;
    // A serial of this process's own: demos running side by side each reconnect to their own emulator
    // (a pty name can be reused by another one's after a simulated disconnect).
    cfg.instrument.serial = "EMU" + std::to_string(10000 + ::getpid() % 90000);
    cfg.machine.geometry = machine.geometry;
    cfg.machine.errors = acq::demo_errors(*type);
    cfg.machine.socket_mm = plan.points.front().socket_mm;
    cfg.machine.start = plan.points.front().pose;
    if (!o.faults.empty()) cfg.faults = parse_faults(o.faults);
    workflow::PtyEmulator emulator(cfg);
    emulator.emulator().machine().keep_history();  // for the truth check of every stored point

    // A killed demo loses at most its last batch; the demo does not need an fsync per commit.
    storage::StoreOptions so;
    so.sync_full = false;
    storage::Store store(resolve_db_path(globals), so);
    storage::NewSession ns;
    ns.machine = machine.geometry;
    ns.source = storage::SessionSource::emulator;
    ns.operator_name = "demo";
    ns.procedure = "ssm-two-step";
    ns.notes = "ballbar demo --machine " + o.machine + " --seed " + std::to_string(o.seed);
    storage::Instrument inst;
    inst.model = cfg.instrument.model;
    inst.serial = cfg.instrument.serial;
    inst.firmware = cfg.instrument.firmware;
    inst.calibrated_length_mm = cfg.instrument.calibrated_length_mm;
    ns.instrument = inst;
    const std::int64_t id = store.create_session(ns);
    store.start_session(id);
    workflow::store_plan(store, id, plan);

    const bool show = !o.json && ::isatty(STDERR_FILENO);
    if (!o.json)
        std::cout << "ballbar demo: " << o.machine << " (" << machine.geometry.name << "), " << plan.test_count()
                  << " two-step tests, " << plan.points.size() << " points; emulator on " << emulator.path() << "\n";
    workflow::DeviceSource source([&emulator] { return device::open_transport("serial:" + emulator.path()); });
    workflow::StoreSink sink(store, id, plan);
    DemoOperator op(plan, emulator.emulator().machine(), show, !o.json, cfg.faults);
    acq::Session session(plan, source, sink, op);
    const acq::SessionSummary sum = session.run();
    sink.finish(sum);
    if (sum.final_state != acq::State::Done) {
        // The points it did store are checked against the truth all the same: an unfinished session
        // must not hide a wrong point either. Its end is told as stored (interrupted, aborted, failed).
        emulator.halt();
        const TruthCheck tc = check_against_truth(store, id, emulator.emulator());
        std::string truth = "; its " + std::to_string(tc.points) + " stored points checked against the truth: ";
        truth += tc.wrong_pose == 0
                     ? "all at their pose"
                     : std::to_string(tc.wrong_pose) + " away from their pose (first: " + tc.first_wrong + ")";
        throw Error(ErrorCategory::failed, "demo session " + std::to_string(id) + " ended " +
                                               std::string(storage::to_string(store.session(id).state)) + ": " +
                                               sum.reason + truth);
    }

    // Compare with the truth.
    const auto truth = acq::true_values(plan, cfg.machine.errors);
    json out;
    out["session"] = id;
    out["machine"] = o.machine;
    out["locations"] = json::array();
    out["orientation"] = json::array();
    std::vector<acq::LocationResult> locs;
    for (const auto& r : store.results(id))
        if (r.kind == acq::kSsmResultKind) locs.push_back(acq::location_from_json(r.payload_json));
    for (const auto& l : locs) {
        const auto& t = truth[static_cast<std::size_t>(l.test)];
        const ba::Vec3 tr = l.step == 1 ? t.e1_mm : t.e2_mm;
        out["locations"].push_back({{"test", l.test + 1},
                                    {"step", l.step},
                                    {"measured_mm", {l.ssm.exact_mm.x(), l.ssm.exact_mm.y(), l.ssm.exact_mm.z()}},
                                    {"std_mm", {l.ssm.std_mm.x(), l.ssm.std_mm.y(), l.ssm.std_mm.z()}},
                                    {"true_mm", {tr.x(), tr.y(), tr.z()}}});
    }
    for (const auto& r : sum.tests) {
        const auto& t = truth[static_cast<std::size_t>(r.test)];
        out["orientation"].push_back(
            {{"test", r.test + 1},
             {"kind", std::string(acq::to_string(r.kind))},
             {"measured_rad", angles_json(r.orientation.exact, *type, r.kind)},
             {"std_rad", angles_json(r.std_rad, *type, r.kind)},  // of measured_rad
             {"true_rad", angles_json(t.result.orientation.exact, *type, r.kind)},
             {"measured_first_order_rad", angles_json(r.orientation.first_order, *type, r.kind)},
             {"true_first_order_rad", angles_json(t.result.orientation.first_order, *type, r.kind)}});
    }
    out["samples"] = sum.samples;
    out["programs"] = sum.programs;
    out["void_dwells"] = sum.void_dwells;
    out["pauses"] = sum.pauses;
    emulator.halt();
    const TruthCheck tc = check_against_truth(store, id, emulator.emulator());
    const auto& ec = emulator.emulator().counters();
    out["truth_check"] = {{"points", tc.points},
                          {"wrong_pose", tc.wrong_pose},
                          {"stored_twice", tc.stored_twice},
                          {"samples_stored", tc.samples_stored},
                          {"dropped_frames", ec.dropped_frames},
                          {"replayed_frames", ec.replayed_frames},
                          {"corrupted_bytes", ec.corrupted_bytes}};
    if (tc.wrong_pose > 0 || tc.stored_twice > 0)
        throw Error(ErrorCategory::failed, "demo session " + std::to_string(id) + ": " + std::to_string(tc.wrong_pose) +
                                               " points stored away from their pose (first: " + tc.first_wrong + "), " +
                                               std::to_string(tc.stored_twice) + " samples stored twice");

    int code = kExitOk;
    std::string compensation_text;  // printed after the session's tables
#ifdef BALLBAR_HAVE_COMPENSATION_DEMO
    if (o.compensate) {
        CompensationDemoOptions co;
        co.seed = o.seed;
        CompensationDemoResult cr;
        std::ostringstream ss;
        code = run_compensation_demo(co, ss, o.json, &cr);
        if (o.json) {
            out["compensation"] = json::parse(ss.str());
            // Issue 6's shape at the top level too: improvement, residual_um, identified (and rms_before_um).
            for (const char* key : {"improvement", "rms_before_um", "residual_um", "identified"})
                out[key] = out["compensation"][key];
        } else {
            compensation_text = ss.str();
        }
        // Stored with the demo session, so its report shows the before/after (report/ reads kind
        // "compensation") -- only with a TTTRR session: the proof runs on an emulated TTTRR machine.
        if (*type == ba::MachineType::TTTRR) {
            json stored;
            stored["metric"] = "RMS tool-ball error over a " + std::to_string(cr.path_blocks) +
                               "-block test path, before and after " + (cr.exact ? "exact" : "first-order") +
                               " compensation (compensation demo: its own emulated TTTRR machine, seed " +
                               std::to_string(o.seed) + ")";
            stored["axes"] = json::array();
            for (int a = 0; a < 3; ++a)
                stored["axes"].push_back({{"axis", std::string(1, "XYZ"[a])},
                                          {"unit", "µm"},
                                          {"before", cr.before_um[a]},
                                          {"after", cr.after_um[a]}});
            store.add_result(id, "compensation", stored.dump(), std::nullopt, "ballbar demo/1");
        }
    }
#else
    if (o.compensate) throw Error(ErrorCategory::failed, "--compensate: this build has no compensation demo");
#endif
    if (!o.report.empty()) {
#ifdef BALLBAR_HAVE_REPORT
        write_output(o.report, "--report", report::render_pdf_bytes(report::build_report(store, id)), inputs);
        out["report"] = o.report;
#else
        throw Error(ErrorCategory::failed, "--report: this build has no report module");
#endif
    }
    if (o.json) {
        std::cout << out.dump() << std::endl;
    } else {
        std::printf("\nTotal position errors e = (b - s)actual - (b - s)nominal, µm (SSM exact, %s layout):\n",
                    std::string(ba::to_string(plan.spec.layout)).c_str());
        std::printf(
            "  test step   measured (x, y, z)              true (x, y, z)                  |diff|   (!! more than "
            "5σ from the truth)\n");
        for (const auto& l : out["locations"]) {
            const auto& m = l["measured_mm"];
            const auto& t = l["true_mm"];
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
                        t["kind"].get<std::string>().c_str(),
                        arcsec(t["measured_rad"], t["std_rad"], t["true_rad"]).c_str(), arcsec(t["true_rad"]).c_str());
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
    sub->callback([o, &globals] { globals.action = [o, &globals] { return run_demo(*o, globals); }; });
}

}  // namespace ballbar::app
