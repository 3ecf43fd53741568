// SPDX-License-Identifier: MIT
// `ballbar circle measure` and `ballbar demo --test circular` (circle_measure.hpp): the circular test's
// procedure (acquisition/circular_session.hpp) on a real instrument or on the emulator's continuous
// machine, stored as a circular session of the same shape an imported trace makes (docs/storage.md),
// so `circle analyze SESSION`, `export --format trace` and `report SESSION` read both alike.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "ballbar/acquisition/circle_program.hpp"
#include "ballbar/acquisition/circular_session.hpp"
#include "ballbar/acquisition/machine_file.hpp"
#include "ballbar/device/emulator_host.hpp"
#include "ballbar/device/gauge.hpp"
#include "ballbar/device/uri.hpp"
#include "ballbar/report/build.hpp"
#include "ballbar/report/report.hpp"
#include "ballbar/storage/trace_file.hpp"
#include "ballbar/version.hpp"
#include "ballbar/workflow/circular_demo.hpp"
#include "ballbar/workflow/circular_measure.hpp"
#include "ballbar/workflow/gauge_source.hpp"
#include "ballbar/workflow/machines.hpp"
#include "ballbar/workflow/session_io.hpp"
#include "circle_measure.hpp"
#include "circle_output.hpp"
#include "circle_test_options.hpp"
#include "files.hpp"
#include "interrupt.hpp"
#include "json_out.hpp"
#include "operators.hpp"
#include "prompt.hpp"
#include "resume_line.hpp"

namespace ballbar::app {
namespace {

namespace acq = ballbar::acquisition;
namespace circ = ballbar::analysis::circular;
using ojson = nlohmann::ordered_json;

// ---- the operator -------------------------------------------------------------------------------------

/// The circular procedure's operator: at a terminal (prompts), scripted (every answer yes, logged), or
/// as JSON event lines (answers from stdin, or scripted). The part program is written to `program_path`
/// when the operator is told to run it.
class CircleOperator : public acq::Operator {
  public:
    enum class Mode { Terminal, Scripted, Json, JsonScripted, Quiet };
    CircleOperator(Mode mode, std::istream& in, std::ostream& out, bool tty, std::string program_path,
                   std::string program_text)
        : mode_(mode),
          in_(in),
          out_(out),
          tty_(tty),
          path_(std::move(program_path)),
          program_(std::move(program_text)),
          prompt_(in, out, reads_terminal(in), tty, InterruptGuard::request) {}

    bool confirm(std::string_view what, std::string_view prompt) override {
        end_line();
        if (mode_ == Mode::Json || mode_ == Mode::JsonScripted) {
            ojson j = {{"event", "question"}, {"what", what}, {"prompt", prompt}, {"options", {"yes", "no"}}};
            bool yes = true;
            if (mode_ == Mode::Json) {
                emit(j);
                const auto a = read_choice(in_, out_, {"yes", "no"});
                yes = a && *a == 0;
            }
            j["event"] = "answer";
            j["answer"] = yes ? "yes" : "no";
            emit(j);
            return yes;
        }
        if (mode_ == Mode::Quiet) return true;
        if (mode_ == Mode::Scripted) {
            out_ << prompt << " [yes]" << std::endl;
            return true;
        }
        if (what == "setup" || what == "reference") return prompt_.ready(prompt);  // "no" is "not yet"
        // The review: "measure again" runs the program again; abort stops, keeping the runs measured.
        const auto a = what == "review" ? prompt_.choose(prompt, {"accept", "measure-again"})
                                        : prompt_.choose(prompt, {"yes", "no"});
        return a && *a == 0;
    }
    std::size_t choose(const acq::Choice& c) override {
        end_line();
        if (mode_ == Mode::Terminal || mode_ == Mode::Json) {
            std::optional<std::size_t> a;
            if (mode_ == Mode::Json) {
                emit({{"event", "question"}, {"what", c.what}, {"prompt", c.prompt}, {"options", c.options}});
                a = read_choice(in_, out_, c.options);
            } else {
                a = prompt_.choose(c.prompt, c.options);
            }
            return a ? *a : c.options.size() - 1;
        }
        if (mode_ == Mode::Scripted) out_ << c.prompt << " [" << c.options[c.default_option] << "]\n";
        if (mode_ == Mode::JsonScripted)
            emit({{"event", "answer"}, {"what", c.what}, {"answer", c.options[c.default_option]}});
        return c.default_option;
    }
    void message(std::string_view text) override {
        end_line();
        if (mode_ == Mode::Quiet) return;
        if (mode_ == Mode::Json || mode_ == Mode::JsonScripted)
            emit({{"event", "message"}, {"text", text}});
        else
            out_ << text << std::endl;
    }
    acq::PointFailureAction point_failed(const acq::CapturedPoint&, std::string_view) override {
        return acq::PointFailureAction::Retry;
    }
    void wait_at_point(const acq::PlannedPoint&) override {}
    void run_program(const analysis::NcProgram&, std::span<const std::size_t>, bool) override {}
    void program_stop(const acq::ProgramStop&) override {}
    void progress(const acq::Progress& p) override {
        if (mode_ == Mode::Json || mode_ == Mode::JsonScripted) {
            if (p.done != last_done_) emit({{"event", "progress"}, {"runs_done", p.done}, {"runs", p.total}});
            last_done_ = p.done;
            return;
        }
        if (!tty_ || mode_ == Mode::Quiet) return;
        const double dev_um = (p.live_mm - p.expected_mm) * 1e3;
        out_ << "\r  runs " << p.done << "/" << p.total;
        if (p.angle_deg) out_ << "  at " << std::fixed << std::setprecision(0) << *p.angle_deg << "°";
        out_ << "  bar " << std::fixed << std::setprecision(4) << p.live_mm << " mm";
        if (p.out_of_range)
            out_ << " (out of range)";
        else
            out_ << " (" << (dev_um >= 0 ? "+" : "") << std::setprecision(1) << dev_um << " µm from the radius)";
        if (p.time_left_s > 0)
            out_ << "  ~" << static_cast<long>(std::lround(p.time_left_s)) << " s left at 100 % feed";
        if (p.start_wait_left_s)
            out_ << "  waiting for the feed-in (the run is given up in "
                 << static_cast<long>(std::lround(*p.start_wait_left_s)) << " s)";
        out_ << "\033[K" << std::flush;
        line_ = true;
    }
    void instrument_waiting(double seconds_left) override {
        if (!tty_ || mode_ == Mode::Quiet || mode_ == Mode::Json || mode_ == Mode::JsonScripted) return;
        out_ << "\r  instrument lost: " << static_cast<long>(std::lround(seconds_left))
             << " s left before the session stops (resumable); reconnect it, or Ctrl-C to stop now\033[K" << std::flush;
        line_ = true;
    }
    void set_program_path(std::string path) { path_ = std::move(path); }
    void set_program(std::string text) { program_ = std::move(text); }
    void run_part_program(std::string_view what, bool retry) override {
        end_line();
        if (!path_.empty()) {
            std::ofstream f(path_, std::ios::binary | std::ios::trunc);
            f << program_;
            if (!f) throw acq::SourceError("cannot write the part program to " + path_);
        }
        if (mode_ == Mode::Json || mode_ == Mode::JsonScripted) {
            emit({{"event", "run_program"}, {"retry", retry}, {"program", path_}, {"what", what}});
            return;
        }
        if (mode_ == Mode::Quiet) return;
        out_ << what;
        if (!path_.empty()) out_ << " (program: " << path_ << ")";
        out_ << std::endl;
    }

  private:
    void emit(const ojson& j) { out_ << j.dump() << std::endl; }
    void end_line() {
        if (line_) out_ << "\n";
        line_ = false;
    }
    Mode mode_;
    std::istream& in_;
    std::ostream& out_;
    bool tty_;
    std::string path_, program_;
    Prompter prompt_;
    bool line_ = false;
    std::size_t last_done_ = static_cast<std::size_t>(-1);
};

// ---- after the procedure ---------------------------------------------------------------------------

// ---- circle measure ------------------------------------------------------------------------------------

struct MeasureOptions {
    std::string device;
    std::string test_file;
    CircleTestOptions test;  ///< without --test
    std::string dialect = "fanuc";
    double dwell_s = 1.0;
    std::string program_file;
    bool feed_in_given = false;  ///< --feed-in on the command line (else fitted to the bar's range)
    std::string resume;
    std::string operator_name;
    std::string machine_file;  ///< --machine: the machine tested (ballbar-machine/1)
    std::string asset;         ///< --asset: the registry's machine tested
    bool non_interactive = false;
    bool json = false;
};

circ::TestSpec test_from_options(const MeasureOptions& o) {
    if (!o.test_file.empty()) {
        try {
            return storage::parse_test_json(read_file(o.test_file, "test header"));
        } catch (const Error&) {
            throw;
        } catch (const std::exception& e) {
            throw Error(ErrorCategory::bad_input, o.test_file + ": " + e.what());
        }
    }
    return circle_test(o.test);
}

int run_circle_measure(const MeasureOptions& o, const Globals& globals) {
    if (o.device.empty()) throw Error(ErrorCategory::bad_input, "--device URI is required");
    // The database is opened once the request is known to be good: a refused command creates none
    // (a resumed session must be in an existing one).
    std::optional<storage::Store> opened;
    const auto dialect = analysis::parse_nc_dialect(o.dialect);
    if (!dialect) throw Error(ErrorCategory::bad_input, "--dialect must be fanuc or linuxcnc");
    const double dwell_s = o.dwell_s;
    if (!(dwell_s >= 0.2 && dwell_s <= 60)) throw Error(ErrorCategory::bad_input, "--dwell must be 0.2 .. 60 s");
    workflow::PreparedCircular prepared;
    prepared.dialect = *dialect;
    prepared.dwell_s = dwell_s;
    try {
        if (!o.resume.empty()) {
            storage::Store& store = opened.emplace(existing_db_path(globals));
            prepared = workflow::resume_circular_session(store, o.resume, *dialect, dwell_s);
            const storage::SessionInfo& before = *prepared.before;
            // With --json, standard output is the events alone (docs/cli.md): the words go to standard error.
            (o.json ? std::cerr : std::cout)
                << "Session " << before.id << " is " << storage::to_string(before.state)
                << (before.reason.empty() ? "" : ": " + state_reason(storage::to_string(before.state), before.reason))
                << std::endl;
        } else {
            prepared.test = test_from_options(o);
            opened.emplace(resolve_db_path(globals));
        }
    } catch (const storage::StorageError& e) {
        throw as_error(e);
    } catch (const std::runtime_error& e) {
        if (dynamic_cast<const Error*>(&e)) throw;
        throw Error(ErrorCategory::bad_input, e.what());
    }
    storage::Store& store = *opened;
    std::string program;
    try {
        program = acq::circular_program(prepared.test, prepared.dialect, prepared.dwell_s);  // the controller's format
    } catch (const acq::PlanError& e) {
        throw Error(ErrorCategory::bad_input, e.what());
    }
    const auto mode = o.json ? (o.non_interactive ? CircleOperator::Mode::JsonScripted : CircleOperator::Mode::Json)
                      : o.non_interactive ? CircleOperator::Mode::Scripted
                                          : CircleOperator::Mode::Terminal;
    const auto program_path = [&o](std::int64_t id) {
        return o.program_file.empty() ? "ballbar-session-" + std::to_string(id) + ".nc" : o.program_file;
    };
    CircleOperator op(mode, std::cin, std::cout, globals.color, prepared.session ? program_path(*prepared.session) : "",
                      program);
    const InterruptGuard interrupt;
    workflow::CircularMeasureOptions mo;
    mo.device_uri = o.device;
    mo.operator_name = o.operator_name;
    if (!o.machine_file.empty() && !o.asset.empty())
        throw Error(ErrorCategory::bad_input,
                    "--machine and --asset: give one (a registered machine is tested with its "
                    "registered file)");
    if (!o.asset.empty()) {
        const acq::MachineFile machine = workflow::registered_machine_file(store, o.asset);
        mo.machine = machine.geometry;
        mo.machine_asset = o.asset;
        mo.tolerance_um = machine.tolerances.circularity_um;
    } else if (!o.machine_file.empty()) {
        try {
            const acq::MachineFile machine = acq::parse_machine_file(read_file(o.machine_file, "machine file"));
            mo.machine = machine.geometry;
            mo.tolerance_um = machine.tolerances.circularity_um;  // the verdict, stored with the result
        } catch (const acq::PlanError& e) {
            throw Error(ErrorCategory::bad_input, o.machine_file + ": " + e.what());
        }
    }
    mo.stop = InterruptGuard::flag();
    // A test the operator did not shape (no --test, no --feed-in) takes the feed-in the bar's range holds;
    // the program and the stored header follow it.
    mo.fit_feed_in = o.test_file.empty() && !o.feed_in_given;
    // The session is made once the instrument is accepted for the test: a refused test leaves none.
    mo.on_session_created = [&](std::int64_t id, const circ::TestSpec& test) {
        op.set_program_path(program_path(id));
        if (!o.json)
            std::cout << "Session " << id << ": circular test in " << circ::plane_name(test.plane) << ", radius "
                      << test.radius_mm << " mm, feed " << test.feed_mm_min << " mm/min, " << test.runs.size()
                      << " runs." << std::endl;
    };
    mo.on_test_fitted = [&](const circ::TestSpec& fitted) {
        op.set_program(acq::circular_program(fitted, prepared.dialect, prepared.dwell_s));
    };
    const workflow::CircularMeasureResult run = workflow::measure_circular(store, prepared, op, mo);
    workflow::throw_unless_completed(
        run.summary, run.session_id,
        resume_command("circular", run.session_id.value_or(0), globals.db_path,
                       device::gauge::hinted_device(run.summary.reason).value_or(o.device), o.program_file));
    const std::int64_t id = *run.session_id;
    const workflow::StoredCircularResult& stored = *run.stored;
    if (o.json) {
        ojson j = ojson::parse(stored.payload_json);
        j["session"] = id;
        std::cout << ojson{{"event", "done"},
                           {"session", id},
                           {"samples", run.summary.samples},
                           {"attempts", run.summary.attempts},
                           {"result", j}}
                         .dump()
                  << std::endl;
    } else {
        print_circle_result(std::cout, stored.result, stored.trace, std::nullopt);
        std::cout << "Session " << id << " completed (" << run.summary.samples << " samples, " << run.summary.attempts
                  << (run.summary.attempts == 1 ? " run" : " runs") << " of the program); result stored.\n";
    }
    return kExitOk;
}

// ---- demo --test circular ------------------------------------------------------------------------------

}  // namespace

int run_circular_demo(const CircularDemoOptions& o, const Globals& globals) {
    const auto plane = circ::parse_plane(o.plane);
    if (!plane) throw Error(ErrorCategory::bad_input, "--plane must be XY, YZ or ZX");
    const double arc = o.arc_deg > 0 ? o.arc_deg : (*plane == circ::Plane::XY ? 360.0 : 180.0);
    MeasureOptions mo;
    mo.test.plane = o.plane;
    mo.test.radius_mm = o.radius_mm;
    mo.test.feed_mm_min = o.feed_mm_min;
    mo.test.feed_in_mm = 0.8;  // the bar's ±1 mm range holds the stand at R + feed-in
    mo.test.arc_deg = arc;
    const circ::TestSpec test = test_from_options(mo);

    storage::StoreOptions so;
    so.sync_full = false;
    storage::Store store(resolve_db_path(globals), so);
    workflow::CircularDemoOptions demo;
    demo.test = test;
    demo.seed = o.seed;
    if (!o.faults.empty()) demo.faults = parse_faults_option(o.faults);
    demo.notes = "ballbar demo --test circular --plane " + o.plane + " --seed " + std::to_string(o.seed);
    demo.on_started = [&](const std::string& pty, std::int64_t) {
        if (!o.json)
            std::cout << "ballbar demo --test circular: " << circ::plane_name(test.plane) << ", radius "
                      << test.radius_mm << " mm, feed " << test.feed_mm_min << " mm/min, data arc " << arc
                      << "°; emulator on " << pty << "\n";
    };
    const bool show = !o.json && ::isatty(STDERR_FILENO);
    std::ostringstream discard;
    CircleOperator op(show ? CircleOperator::Mode::Scripted : CircleOperator::Mode::Quiet, std::cin,
                      show ? std::cerr : static_cast<std::ostream&>(discard), false, "", "");
    const workflow::CircularDemoResult run = workflow::run_circular_demo(store, demo, op);
    const std::int64_t id = run.session;
    const acq::CircularSummary& sum = run.summary;
    const circ::CircularResult& result = run.result;
    const auto& checks = run.checks;
    const bool pass = run.pass;
    ojson diags = ojson::array();
    for (const auto& c : checks) {
        diags.push_back({{"key", c.key},
                         {"unit", circ::diagnostic_unit(c.diag)},
                         {"value", c.measured ? ojson(*c.measured) : ojson(nullptr)},
                         {"value_std", c.measured ? ojson(c.std_uncertainty) : ojson(nullptr)},
                         {"true_value", c.truth},
                         {"allowed_error", c.allowed},
                         {"injected", c.injected},
                         {"pass", c.pass},
                         {"note", text_or_null(c.note)}});
    }
    ojson out = {
        {"session", id},
        {"plane", circ::plane_name(test.plane)},
        {"radius_mm", test.radius_mm},
        {"feed_mm_min", test.feed_mm_min},
        {"data_arc_deg", arc},
        {"attempts", sum.attempts},
        {"samples", sum.samples},
        {"pauses", sum.pauses},
        {"gaps", sum.gaps},
        {"lost_samples", sum.lost_samples},
        {"duplicates_dropped", sum.duplicates_dropped},
        {"dropped_frames", run.dropped_frames},
        {"replayed_frames", run.replayed_frames},
        {"runs", ojson::array()},
        {"bidirectional_circularity_um", result.bidirectional_um ? ojson(*result.bidirectional_um) : ojson(nullptr)},
        {"hysteresis_um", result.hysteresis_um ? ojson(*result.hysteresis_um) : ojson(nullptr)},
        {"diagnostics", diags},
        {"pass", pass}};
    for (const auto& r : result.runs)
        out["runs"].push_back({{"direction", circ::direction_name(r.direction)}, {"circularity_um", r.circularity_um}});
    if (!o.report.empty()) {
        report::BuildOptions bo;
        bo.software_version = kVersion;
        write_output(o.report, "--report", report::render_pdf_bytes(report::build_report(store, id, bo)),
                     database_files(globals));
        out["report"] = o.report;
    }
    if (o.json) {
        std::cout << out.dump() << std::endl;
    } else {
        std::printf(
            "\nDiagnostics against the emulator's truth (rule of docs/circular.md: 20 %% or 0.25 µm radial;\n"
            "pitch and frequency 5 %%; where nothing was injected, below twice that):\n");
        std::printf("  %-28s %12s %10s %12s %10s  %s\n", "diagnostic", "measured", "± u", "truth", "allowed", "");
        for (const auto& c : checks) {
            if (c.measured)
                std::printf("  %-28s %12.3f %10.3f %12.3f %10.3f  %s\n", c.key.c_str(), *c.measured, c.std_uncertainty,
                            c.truth, c.allowed, c.pass ? "ok" : "MISSED");
            else
                std::printf("  %-28s %23s %12.3f %10.3f  %s\n", c.key.c_str(), c.note.c_str(), c.truth, c.allowed,
                            c.pass ? "ok" : "MISSED");
        }
        for (const auto& r : result.runs)
            std::printf("G %s: %.3f µm\n", circ::direction_name(r.direction), r.circularity_um);
        if (result.bidirectional_um) std::printf("G(b): %.3f µm\n", *result.bidirectional_um);
        if (result.hysteresis_um) std::printf("H: %.3f µm\n", *result.hysteresis_um);
        std::printf("Session %lld stored in %s (%zu samples, %d run%s of the program).\n", static_cast<long long>(id),
                    store.path().c_str(), sum.samples, sum.attempts, sum.attempts == 1 ? "" : "s");
        if (!o.report.empty()) std::printf("Report written to %s.\n", o.report.c_str());
    }
    if (!pass)
        throw Error(ErrorCategory::failed,
                    "demo session " + std::to_string(id) +
                        ": a diagnostic missed the emulator's truth by more than the accuracy rule");
    return kExitOk;
}

void add_circle_measure(CLI::App& circle, Globals& globals) {
    auto o = std::make_shared<MeasureOptions>();
    auto* m = circle.add_subcommand("measure", "Measure a circular test on an instrument (guided)");
    m->add_option("--device", o->device, "Instrument URI (serial:PATH, tcp:HOST:PORT, usb:…, sylvac:PATH, …)");
    m->add_option("--test", o->test_file, "the test header (JSON) of `circle plan --test-out`");
    m->add_option("--plane", o->test.plane, "XY, YZ or ZX (without --test)")->capture_default_str();
    add_circle_geometry_options(*m, o->test, "feed, mm/min");
    auto* feed_in = m->add_option("--feed-in", o->test.feed_in_mm,
                                  "radial feed-in and feed-out, mm (default: 1.5, or less to keep the stand within "
                                  "the bar's range)")
                        ->check(in_range(0, 10, "mm", true));
    m->add_option("--arc", o->test.arc_deg, "data arc, degrees (360 full circle; 180 the partial arc)")
        ->check(in_range(30, 360, "°"))
        ->capture_default_str();
    m->add_option("--dialect", o->dialect, "part program dialect: fanuc or linuxcnc")->capture_default_str();
    m->add_option("--dwell", o->dwell_s, "stand before each feed-in, s")
        ->check(in_range(0.2, 60, "s"))
        ->capture_default_str();
    m->add_option("--program", o->program_file, "where to write the part program (default ballbar-session-ID.nc)");
    m->add_option("--resume", o->resume, "continue an interrupted circular session (id or uuid prefix)");
    m->add_option("--operator", o->operator_name, "operator name stored with the session");
    m->add_option("--machine", o->machine_file,
                  "the machine tested (its machine file): the session is listed and trended under it");
    m->add_option("--asset", o->asset,
                  "the registry's machine tested (ballbar machines add), instead of --machine: its tolerance judges "
                  "G, and the session is listed and trended under its asset id");
    m->add_flag("--non-interactive", o->non_interactive, "answer every question yes (logged)");
    m->add_flag("--json", o->json, "events as JSON lines on stdout (answers from stdin unless --non-interactive)");
    m->callback([o, feed_in, &globals] {
        o->feed_in_given = feed_in->count() > 0;
        globals.action = [o, &globals] { return run_circle_measure(*o, globals); };
    });
}

}  // namespace ballbar::app
