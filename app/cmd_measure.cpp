// SPDX-License-Identifier: MIT
// `ballbar measure`: the guided two-step SSM procedure on a real (or emulated) instrument. Interactive
// by default (prompts, a progress bar with the live bar reading); `--non-interactive` takes the plan
// file's answers. Everything is stored as it happens; `--resume SESSION` continues an interrupted
// session after its last completed point. docs/procedure.md describes the procedure and the files.
#include <unistd.h>

#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include "acquisition_adapters.hpp"
#include "ballbar/acquisition/bar_check.hpp"
#include "ballbar/acquisition/nc_writer.hpp"
#include "ballbar/acquisition/session.hpp"
#include "ballbar/device/uri.hpp"
#include "command.hpp"
#include "gauge_source.hpp"
#include "interrupt.hpp"

namespace ballbar::app {
namespace {

namespace acq = ballbar::acquisition;
namespace ba = ballbar::analysis;

struct MeasureOptions {
    std::string device;
    std::string machine_file;
    std::string plan_file;
    std::string operator_name;
    std::string resume;
    std::string program_file;
    bool non_interactive = false;
    bool dry_run = false;
    std::size_t from_point = 0;
};

/// Plan-file answers, with the prompts and progress written to `out` line by line (logs, CI).
class ScriptedTerminalOperator : public TerminalOperator {
  public:
    ScriptedTerminalOperator(std::ostream& out, const acq::Plan& plan, std::string program)
        : TerminalOperator(empty_, out, false, plan, std::move(program)), out_(out), answers_(plan.spec.answers) {}
    bool confirm(std::string_view what, std::string_view prompt) override {
        const bool yes = acq::ScriptedOperator(answers_).confirm(what, prompt);
        out_ << prompt << " [plan: " << (yes ? "yes" : "no") << "]\n";
        return yes;
    }
    acq::PointFailureAction point_failed(const acq::CapturedPoint& p, std::string_view why) override {
        out_ << "point test " << p.planned.test + 1 << " step " << p.planned.step << " point " << p.planned.point + 1
             << " failed: " << why << "\n";
        return answers_.on_point_failure;
    }
    void wait_at_point(const acq::PlannedPoint&) override {}
    void progress(const acq::Progress& p) override {
        if (p.done == last_) return;
        last_ = p.done;
        out_ << "captured " << p.done << "/" << p.total << "\n" << std::flush;
    }

  private:
    std::istringstream empty_;
    std::ostream& out_;
    acq::Answers answers_;
    std::size_t last_ = static_cast<std::size_t>(-1);
};

void print_results(std::ostream& out, const acq::SessionSummary& sum) {
    for (const auto& t : sum.tests) {
        out << "test " << t.test + 1 << " (" << acq::to_string(t.kind) << "): ΔV1 [µm] " << (t.dV1_mm * 1e3).transpose()
            << ", ΔV2 [µm] " << (t.dV2_mm * 1e3).transpose() << "\n";
        if (t.orientation.exact) {
            const auto& e = *t.orientation.exact;
            out << "  orientation (exact) [arcsec]: Δα " << ba::rad_to_arcsec(e.d_alpha_rad) << "  Δβ "
                << ba::rad_to_arcsec(e.d_beta_rad) << "  Δγ " << ba::rad_to_arcsec(e.d_gamma_rad) << "\n";
        } else {
            out << "  orientation: " << t.orientation.singular << "\n";
        }
    }
}

/// The identity the instrument reported, stored with the session (sessions show, the report).
void record_instrument(storage::Store& store, std::int64_t id, const device::InstrumentInfo& info) {
    storage::Instrument in;
    in.model = info.model;
    in.serial = info.serial;
    in.firmware = info.firmware;
    in.calibrated_length_mm = info.calibrated_length_mm;
    in.calibration_date = info.calibration_date;
    store.set_instrument(id, in);
}

/// --dry-run: plan, check and write the NC program; no instrument, no database.
int dry_run(const MeasureOptions& o) {
    if (o.machine_file.empty()) throw CliError(kExitUsage, "--machine FILE is required");
    try {
        const acq::MachineFile machine = acq::parse_machine_file(read_file(o.machine_file, "machine file"));
        const acq::PlanSpec spec =
            o.plan_file.empty() ? acq::default_plan(machine)
                                : acq::parse_plan_file(read_file(o.plan_file, "plan file"), machine.geometry.type);
        const acq::Plan plan = acq::make_plan(machine, spec);
        if (o.from_point >= plan.points.size())
            throw CliError(kExitUsage, "--from-point " + std::to_string(o.from_point) + ": the plan has " +
                                           std::to_string(plan.points.size()) + " points");
        const std::string text = acq::write_plan_program(plan, o.from_point);
        if (o.program_file.empty()) {
            std::cout << text;
            return kExitOk;
        }
        std::ofstream f(o.program_file);
        f << text;
        if (!f) throw CliError(kExitFailure, "cannot write " + o.program_file);
        std::cout << "Plan checked: " << plan.test_count() << " tests, " << plan.points.size()
                  << " points within the travel; NC program written to " << o.program_file << "\n";
        return kExitOk;
    } catch (const acq::PlanError& e) {
        throw CliError(kExitUsage, e.what());
    }
}

int run_measure(const MeasureOptions& o, const Globals& globals) {
    if (o.dry_run) return dry_run(o);
    storage::Store store(resolve_db_path(globals));
    std::int64_t id = 0;
    acq::Plan plan;
    std::vector<acq::CapturedPoint> done;
    try {
        if (!o.resume.empty()) {
            id = store.find_session(o.resume);
            const storage::SessionInfo before = store.session(id);  // why it stopped, shown first
            std::cout << "Session " << id << " is " << storage::to_string(before.state)
                      << (before.reason.empty() ? "" : ": " + before.reason) << "\n";
            plan = load_plan(store, id);
            done = load_points(store, id, plan);
            store.resume_session(id);
        } else {
            if (o.machine_file.empty()) throw CliError(kExitUsage, "--machine FILE is required (or --resume SESSION)");
            const acq::MachineFile machine = acq::parse_machine_file(read_file(o.machine_file, "machine file"));
            acq::PlanSpec spec = o.plan_file.empty()
                                     ? acq::default_plan(machine)
                                     : acq::parse_plan_file(read_file(o.plan_file, "plan file"), machine.geometry.type);
            if (!o.operator_name.empty()) spec.answers.operator_name = o.operator_name;
            plan = acq::make_plan(machine, spec);
            storage::NewSession ns;
            ns.machine = machine.geometry;
            ns.source =
                o.device.rfind("emulator:", 0) == 0 ? storage::SessionSource::emulator : storage::SessionSource::device;
            ns.operator_name = spec.answers.operator_name;
            ns.procedure = "ssm-two-step";
            id = store.create_session(ns);
            store.start_session(id);
            store_plan(store, id, plan);
        }
    } catch (const acq::PlanError& e) {
        throw CliError(kExitUsage, e.what());
    }
    if (o.device.empty()) throw CliError(kExitUsage, "--device URI is required");
    std::cout << "Session " << id << (done.empty() ? "" : " (resumed after " + std::to_string(done.size()) + " points)")
              << ": " << ba::to_string(plan.machine.geometry.type) << ", " << plan.test_count() << " tests, "
              << plan.points.size() << " points.\n";
    const std::string program =
        o.program_file.empty() ? "ballbar-session-" + std::to_string(id) + ".nc" : o.program_file;

    std::unique_ptr<acq::Operator> op;
    if (o.non_interactive)
        op = std::make_unique<ScriptedTerminalOperator>(std::cout, plan, program);
    else
        op = std::make_unique<TerminalOperator>(std::cin, std::cout, globals.color, plan, program);
    const std::string uri = o.device;
    DeviceSource source([uri] {
        try {
            return device::open_transport(uri);
        } catch (const std::invalid_argument& e) {
            throw acq::SourceError(e.what());
        }
    });
    source.on_identified = [&store, id, &plan, &o](const device::InstrumentInfo& info) {
        record_instrument(store, id, info);
        const std::string mismatch = acq::bar_length_mismatch(plan.spec.bar_length_mm, info.calibrated_length_mm,
                                                              plan.spec.capture.tolerance_mm, o.plan_file);
        if (!mismatch.empty()) throw acq::SourceError(mismatch);
    };
    StoreSink sink(store, id, plan);
    const InterruptGuard interrupt;  // Ctrl-C: stop, store, stay resumable, exit 3
    acq::SessionOptions options;
    options.stop = InterruptGuard::flag();
    const auto gauge = make_gauge_source(uri, plan.spec.bar_length_mm);  // a digital gauge (gauge_source.hpp)
    acq::Session session(plan, gauge ? *gauge : static_cast<acq::SampleSource&>(source), sink, *op, options);
    session.restore(done);
    const acq::SessionSummary sum = session.run();
    sink.finish(sum);
    if (sum.interrupted)
        throw CliError(kExitInterrupted, "session " + std::to_string(id) + " interrupted after " +
                                             std::to_string(sum.samples) +
                                             " samples; everything measured is stored. Continue it with: ballbar "
                                             "measure --resume " +
                                             std::to_string(id) + " --device " + o.device);
    if (sum.final_state == acq::State::Done) {
        print_results(std::cout, sum);
        std::cout << "Session " << id << " completed (" << sum.samples << " samples).\n";
        return kExitOk;
    }
    if (sum.final_state == acq::State::Aborted)
        throw CliError(kExitInterrupted, "session " + std::to_string(id) + " aborted: " + sum.reason);
    throw CliError(kExitFailure, "session " + std::to_string(id) + " failed: " + sum.reason);
}

}  // namespace

BALLBAR_COMMAND(measure) {
    auto* sub = root.add_subcommand("measure", "Guided two-step SSM measurement (RRTTT, TTTRR, RTTTR)");
    auto o = std::make_shared<MeasureOptions>();
    sub->add_option("--device", o->device, "Instrument URI (serial:PATH, tcp:HOST:PORT, usb:VID:PID, emulator:CONFIG)");
    sub->add_option("--machine", o->machine_file, "Machine file (ballbar-machine/1 JSON)");
    sub->add_option("--plan", o->plan_file, "Plan file (ballbar-plan/1 JSON); default: four tests at one socket");
    sub->add_option("--operator", o->operator_name, "Operator name stored with the session");
    sub->add_option("--resume", o->resume, "Continue an interrupted session (id or uuid prefix)");
    sub->add_option("--program", o->program_file, "Where to write the NC program (default ballbar-session-ID.nc)");
    sub->add_flag("--dry-run", o->dry_run, "Check the plan and write the NC program (stdout or --program) only");
    sub->add_option("--from-point", o->from_point, "With --dry-run: the program from this point (0-based) on");
    sub->add_flag("--non-interactive", o->non_interactive, "Take every answer from the plan file");
    sub->callback([o, &globals] { globals.action = [o, &globals] { return run_measure(*o, globals); }; });
}

}  // namespace ballbar::app
