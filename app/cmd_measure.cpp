// SPDX-License-Identifier: MIT
// `ballbar measure`: the guided two-step SSM procedure on a real (or emulated) instrument. Interactive
// by default (prompts, a progress bar with the live bar reading); `--non-interactive` takes the plan
// file's answers. Everything is stored as it happens; `--resume SESSION` continues an interrupted
// session after its last completed point. docs/procedure.md describes the procedure and the files.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "ballbar/acquisition/bar_check.hpp"
#include "ballbar/acquisition/nc_writer.hpp"
#include "ballbar/acquisition/session.hpp"
#include "ballbar/device/emulator.hpp"
#include "ballbar/device/gauge.hpp"
#include "ballbar/device/uri.hpp"
#include "ballbar/workflow/machines.hpp"
#include "ballbar/workflow/measure.hpp"
#include "command.hpp"
#include "figures.hpp"
#include "files.hpp"
#include "interrupt.hpp"
#include "json_out.hpp"
#include "operators.hpp"
#include "resume_line.hpp"

namespace ballbar::app {
namespace {

namespace acq = ballbar::acquisition;
namespace ba = ballbar::analysis;

struct MeasureOptions {
    std::string device;
    std::string machine_file;
    std::string asset;  ///< --asset: the registry's machine instead of a machine file
    std::string plan_file;
    std::string operator_name;
    std::string resume;
    std::string program_file;
    bool non_interactive = false;
    bool dry_run = false;
    bool json = false;
    std::size_t from_point = 0;
};

void print_results(std::ostream& out, const acq::Plan& plan, const acq::SessionSummary& sum) {
    const ba::MachineType type = plan.machine.geometry.type;
    // The verdict first, as the report's summary: the machine file's tolerances (none: no verdict).
    if (const acq::SsmVerdict v = acq::judge_ssm(type, plan.machine.tolerances, plan.spec.tests, sum.tests); v.judged())
        out << v.summary() << "\n";
    for (const auto& t : sum.tests) {
        out << "test " << t.test + 1 << " (" << acq::to_string(t.kind) << "):\n  ΔV1 "
            << vec_um(t.dV1_mm, t.dV1_std_mm.norm() > 0 ? &t.dV1_std_mm : nullptr) << "\n  ΔV2 "
            << vec_um(t.dV2_mm, t.dV2_std_mm.norm() > 0 ? &t.dV2_std_mm : nullptr) << "\n";
        if (!t.orientation.exact) {
            out << "  orientation: " << t.orientation.singular << "\n";
            continue;
        }
        const auto& e = *t.orientation.exact;
        std::ostringstream os;
        os.setf(std::ios::fixed);
        os.precision(2);
        auto ang = [&](const char* name, double v, std::optional<double> sd) {
            os << "  " << name << " " << ba::rad_to_arcsec(v) << "″";
            if (sd) os << " ± " << ba::rad_to_arcsec(*sd) << "″";
        };
        const ba::MeasuredAngles angles = acq::measured_angles(type, t.kind);
        os << "  orientation (exact):";
        if (angles.alpha) ang("Δα", e.d_alpha_rad, t.std_rad ? std::optional(t.std_rad->d_alpha_rad) : std::nullopt);
        if (angles.beta) ang("Δβ", e.d_beta_rad, t.std_rad ? std::optional(t.std_rad->d_beta_rad) : std::nullopt);
        if (angles.gamma) ang("Δγ", e.d_gamma_rad, t.std_rad ? std::optional(t.std_rad->d_gamma_rad) : std::nullopt);
        out << os.str() << "\n";
    }
}

/// What --program must never replace: the machine and plan files, the database.
std::vector<fileio::Protected> measure_inputs(const MeasureOptions& o, const std::string& db) {
    std::vector<fileio::Protected> inputs = {{o.machine_file, "machine file"}, {o.plan_file, "plan file"}};
    if (!db.empty())
        for (const char* side : {"", "-wal", "-shm", "-journal"}) inputs.push_back({db + side, "database"});
    return inputs;
}

/// --dry-run: plan, check and write the NC program; no instrument, no database.
int dry_run(const MeasureOptions& o, const Globals& globals) {
    if (o.machine_file.empty() && o.asset.empty())
        throw Error(ErrorCategory::bad_input, "--machine FILE (or --asset ID) is required");
    try {
        const acq::MachineFile machine = [&] {
            if (o.asset.empty()) return acq::parse_machine_file(read_file(o.machine_file, "machine file"));
            storage::StoreOptions so;
            so.recover = false;
            storage::Store store(existing_db_path(globals), so);
            return workflow::registered_machine_file(store, o.asset);
        }();
        const acq::PlanSpec spec =
            o.plan_file.empty() ? acq::default_plan(machine)
                                : acq::parse_plan_file(read_file(o.plan_file, "plan file"), machine.geometry.type);
        const acq::Plan plan = acq::make_plan(machine, spec);
        if (o.from_point >= plan.points.size())
            throw Error(ErrorCategory::bad_input, "--from-point " + std::to_string(o.from_point) + ": the plan has " +
                                                      std::to_string(plan.points.size()) + " points");
        const std::string text = acq::write_plan_program(plan, o.from_point);
        if (o.program_file.empty()) {
            std::cout << text;
            return kExitOk;
        }
        write_output(o.program_file, "--program", text, measure_inputs(o, globals.db_path));
        std::cout << "Plan checked: " << count_of(plan.test_count(), "test") << ", " << plan.points.size()
                  << " points within the travel; NC program written to " << o.program_file << "\n";
        return kExitOk;
    } catch (const acq::PlanError& e) {
        throw Error(ErrorCategory::bad_input, e.what());
    }
}

/// A device URI that cannot name an instrument (and an emulator configuration that cannot be read) is a
/// bad command line: exit 2, found before anything is stored.
void check_device_uri(const std::string& uri) {
    try {
        if (device::gauge::is_gauge_uri(uri)) {
            (void)device::gauge::bar_from_uri(uri, {});
        } else if (const device::DeviceUri d = device::parse_device_uri(uri);
                   d.scheme == device::DeviceUri::Scheme::Emulator && !d.path.empty()) {
            (void)device::load_emulator_config(d.path);
        }
    } catch (const std::invalid_argument& e) {
        throw Error(ErrorCategory::bad_input, "--device: " + std::string(e.what()));
    }
}

/// Everything a command line can get wrong, checked before a database is opened: a refused command
/// line leaves no session and creates no database (docs/cli.md).
void check_command_line(const MeasureOptions& o) {
    if (o.resume.empty() && o.machine_file.empty() && o.asset.empty())
        throw Error(ErrorCategory::bad_input, "--machine FILE or --asset ID is required (or --resume SESSION)");
    if (!o.machine_file.empty() && !o.asset.empty())
        throw Error(ErrorCategory::bad_input,
                    "--machine and --asset: give one (a registered machine measures with its registered file)");
    if (o.device.empty()) throw Error(ErrorCategory::bad_input, "--device URI is required");
    check_device_uri(o.device);
    // The terminal operator asks its questions on standard input; a script or a CI job has none to
    // answer them (they would read end-of-file as "no" and stop the session).
    if (!o.json && !o.non_interactive && !::isatty(STDIN_FILENO))
        throw Error(ErrorCategory::bad_input,
                    "standard input is not a terminal, so nobody can answer measure's questions: add "
                    "--non-interactive (the answers of the plan file's \"answers\") or --json (answers as JSON "
                    "lines on standard input)");
}

/// The plan of a new session, from --machine (or the registry's machine, `registered`) and --plan
/// (exit 2 when either is malformed).
acq::Plan new_plan(const MeasureOptions& o, const std::optional<acq::MachineFile>& registered) {
    try {
        const acq::MachineFile machine =
            registered ? *registered : acq::parse_machine_file(read_file(o.machine_file, "machine file"));
        acq::PlanSpec spec = o.plan_file.empty()
                                 ? acq::default_plan(machine)
                                 : acq::parse_plan_file(read_file(o.plan_file, "plan file"), machine.geometry.type);
        if (!o.operator_name.empty()) spec.answers.operator_name = o.operator_name;
        acq::Plan plan = acq::make_plan(machine, spec);
        (void)acq::write_plan_program(plan, 0);  // every NC word in the controller's format, before a session
        return plan;
    } catch (const acq::PlanError& e) {
        throw Error(ErrorCategory::bad_input, e.what());
    }
}

int run_measure(const MeasureOptions& o, const Globals& globals) {
    if (o.dry_run) return dry_run(o, globals);
    check_command_line(o);
    if (!o.program_file.empty()) {
        try {
            fileio::check_output(o.program_file, "--program", measure_inputs(o, resolve_db_path(globals)));
        } catch (const fileio::FileError& e) {
            throw as_error(e);
        }
    }
    std::unique_ptr<storage::Store> opened;
    workflow::PreparedSession prepared;
    if (!o.resume.empty()) {
        // A session is continued in an existing database only (a mistyped --db is not a new file).
        opened = std::make_unique<storage::Store>(existing_db_path(globals));
        // Why it stopped is shown first, also when it cannot be continued.
        try {
            const storage::SessionInfo before = opened->session(opened->find_session(o.resume));
            // With --json, standard output is the events alone (docs/cli.md): the words go to standard error.
            (o.json ? std::cerr : std::cout)
                << "Session " << before.id << " is " << storage::to_string(before.state)
                << (before.reason.empty() ? "" : ": " + state_reason(storage::to_string(before.state), before.reason))
                << "\n";
        } catch (const storage::StorageError& e) {
            throw as_error(e);  // no such session: exit 2, as `sessions show` says it
        }
        prepared = workflow::resume_ssm_session(*opened, o.resume);
    } else {
        std::optional<acq::MachineFile> registered;
        if (!o.asset.empty()) {
            opened = std::make_unique<storage::Store>(existing_db_path(globals));  // the registry is in it
            registered = workflow::registered_machine_file(*opened, o.asset);
        }
        const acq::Plan plan = new_plan(o, registered);
        if (!opened) opened = std::make_unique<storage::Store>(resolve_db_path(globals));
        prepared = workflow::new_ssm_session(*opened, plan, o.device, o.asset);
    }
    storage::Store& store = *opened;
    const std::int64_t id = prepared.id;
    const acq::Plan& plan = prepared.plan;
    const std::vector<acq::CapturedPoint>& done = prepared.done;
    (o.json ? std::cerr : std::cout) << "Session " << id
                                     << (done.empty() ? ""
                                                      : " (resumed after " + std::to_string(done.size()) + " points)")
                                     << ": " << ba::to_string(plan.machine.geometry.type) << ", "
                                     << count_of(plan.test_count(), "test") << ", "
                                     << count_of(plan.points.size(), "point") << ".\n";
    const std::string program =
        o.program_file.empty() ? "ballbar-session-" + std::to_string(id) + ".nc" : o.program_file;

    std::unique_ptr<acq::Operator> op;
    if (o.json)
        op = std::make_unique<JsonOperator>(std::cin, std::cout, o.non_interactive, plan, program);
    else if (o.non_interactive)
        op = std::make_unique<ScriptedTerminalOperator>(std::cout, plan, program);
    else
        op = std::make_unique<TerminalOperator>(std::cin, std::cout, globals.color, plan, program);
    const InterruptGuard interrupt;  // Ctrl-C: stop, store, stay resumable, exit 3
    workflow::SsmMeasureOptions mo;
    mo.device_uri = o.device;
    mo.plan_file = o.plan_file;
    mo.stop = InterruptGuard::flag();
    const acq::SessionSummary sum = workflow::measure_ssm(store, prepared, *op, mo);
    if (sum.interrupted) {
        std::string retry;
        if (!sum.missing.empty()) {
            // The program for exactly the missing points, for the operator to look at (resume writes it
            // again, with the program stop before its rapid).
            // Beside the program (the directory the operator chose with --program, if any).
            const std::filesystem::path given(program);
            const std::string path =
                (given.parent_path() / (given.stem().string() + "-retry" + given.extension().string())).string();
            try {
                write_program_file(path, acq::make_measuring_program(plan, sum.missing).nc);
                retry = "; the " + std::to_string(sum.missing.size()) + " missing points' program is " + path;
            } catch (const std::exception&) {
            }
        }
        throw Error(ErrorCategory::interrupted,
                    "session " + std::to_string(id) + " interrupted after " + std::to_string(sum.samples) +
                        " samples (" + sum.reason + "); everything measured is stored" + retry +
                        ". Continue it with: " +
                        resume_command("ssm", id, globals.db_path,
                                       device::gauge::hinted_device(sum.reason).value_or(o.device), o.program_file));
    }
    if (sum.final_state == acq::State::Done) {
        if (o.json) {
            nlohmann::ordered_json j = {
                {"event", "done"},
                {"session", id},
                {"samples", sum.samples},
                {"programs", sum.programs},
                {"verdict", verdict_json(acq::judge_ssm(plan.machine.geometry.type, plan.machine.tolerances,
                                                        plan.spec.tests, sum.tests))}};
            std::cout << j.dump() << std::endl;
        } else {
            print_results(std::cout, plan, sum);
            std::cout << "Session " << id << " completed (" << sum.samples << " samples, " << sum.programs
                      << (sum.programs == 1 ? " program" : " programs") << ").\n";
        }
        return kExitOk;
    }
    // Not interrupted: a point that failed its checks with the answer "abort" (the plan's in CI), results
    // not accepted, a set-up not confirmed. The measurement failed (exit 1); 3 is only an interruption.
    if (sum.final_state == acq::State::Aborted)
        throw Error(ErrorCategory::failed, "session " + std::to_string(id) + " aborted: " + sum.reason);
    throw Error(ErrorCategory::failed, "session " + std::to_string(id) + " failed: " + sum.reason);
}

}  // namespace

BALLBAR_COMMAND(measure) {
    auto* sub = root.add_subcommand("measure", "Guided two-step SSM measurement (RRTTT, TTTRR, RTTTR)");
    auto o = std::make_shared<MeasureOptions>();
    // Required, but not always: CLI11's ->required() cannot say "unless --resume", so the help says it.
    sub->add_option("--device", o->device,
                    "REQUIRED (not with --dry-run): instrument URI (serial:PATH, tcp:HOST:PORT, usb:VID:PID, "
                    "hid:VID:PID, emulator:CONFIG, or a gauge's: sylvac:PATH, ...)");
    sub->add_option("--machine", o->machine_file,
                    "REQUIRED (not with --resume): machine file (ballbar-machine/1 JSON)");
    sub->add_option("--asset", o->asset,
                    "the registry's machine (ballbar machines add), instead of --machine: its machine file, and "
                    "the session listed and trended under it");
    sub->add_option("--plan", o->plan_file, "Plan file (ballbar-plan/1 JSON); default: four tests at one socket");
    sub->add_option("--operator", o->operator_name, "Operator name stored with the session");
    sub->add_option("--resume", o->resume, "Continue an interrupted session (id or uuid prefix)");
    sub->add_option("--program", o->program_file, "Where to write the NC program (default ballbar-session-ID.nc)");
    sub->add_flag("--dry-run", o->dry_run, "Check the plan and write the NC program (stdout or --program) only");
    sub->add_option("--from-point", o->from_point, "With --dry-run: the program from this point (0-based) on")
        ->check(in_range(0, 1e6));
    sub->add_flag("--non-interactive", o->non_interactive, "Take every answer from the plan file");
    sub->add_flag("--json", o->json, "Events as JSON lines on stdout (answers from stdin, or the plan's)");
    sub->callback([o, &globals] { globals.action = [o, &globals] { return run_measure(*o, globals); }; });
}

}  // namespace ballbar::app
