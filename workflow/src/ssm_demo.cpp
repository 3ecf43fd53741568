// SPDX-License-Identifier: MIT
#include "ballbar/workflow/ssm_demo.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "ballbar/acquisition/result_codec.hpp"
#include "ballbar/device/uri.hpp"
#include "ballbar/workflow/error.hpp"
#include "ballbar/workflow/pty_emulator.hpp"
#include "ballbar/workflow/session_io.hpp"

namespace ballbar::workflow {

namespace acq = ballbar::acquisition;
namespace ba = ballbar::analysis;

void EmulatedOperator::run_program(const ba::NcProgram& program, std::span<const std::size_t>, bool) {
    machine_.stop(0);  // stops wherever it is now
    machine_.set_feed_override(feed_override_);
    if (start_delay_s_ > 0) machine_.dwell(start_delay_s_);
    machine_.run_program(program);
    ++programs;
}

void EmulatedOperator::program_stop(const acq::ProgramStop& stop) {
    if (stop.socket_mm) machine_.set_socket_mm(*stop.socket_mm);
    if (answer_delay_s_ > 0) machine_.dwell(answer_delay_s_);  // stands at the stop, then cycle start
    machine_.cycle_start(0);                                   // the rest runs once the machine stands at the stop
}

namespace {

/// The front end's operator at the emulated machine: its answers and acknowledgements, then the machine
/// does what it was told (runs the program, moves the socket, cycle start).
class FrontAtMachine : public acq::Operator {
  public:
    FrontAtMachine(acq::Operator& front, EmulatedOperator& machine) : front_(front), machine_(machine) {}
    bool confirm(std::string_view what, std::string_view prompt) override { return front_.confirm(what, prompt); }
    std::size_t choose(const acq::Choice& c) override { return front_.choose(c); }
    void message(std::string_view text) override { front_.message(text); }
    acq::PointFailureAction point_failed(const acq::CapturedPoint& p, std::string_view why) override {
        return front_.point_failed(p, why);
    }
    void wait_at_point(const acq::PlannedPoint& p) override { front_.wait_at_point(p); }
    void progress(const acq::Progress& p) override { front_.progress(p); }
    void run_program(const ba::NcProgram& program, std::span<const std::size_t> points, bool retry) override {
        front_.run_program(program, points, retry);
        machine_.run_program(program, points, retry);
    }
    void program_stop(const acq::ProgramStop& stop) override {
        front_.program_stop(stop);
        machine_.program_stop(stop);
    }
    void point_captured(const acq::CapturedPoint& p) override { front_.point_captured(p); }
    void instrument_lost(double timeout_s) override { front_.instrument_lost(timeout_s); }
    void instrument_back() override { front_.instrument_back(); }

  private:
    acq::Operator& front_;
    EmulatedOperator& machine_;
};

}  // namespace

TruthCheck check_against_truth(storage::Store& store, std::int64_t id, const device::Emulator& emu, double linear_mm,
                               double angle_rad) {
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
            ok = t && (t->pose.linear_mm() - want.linear_mm()).norm() < linear_mm &&
                 std::abs(t->pose.A_rad - want.A_rad) < angle_rad && std::abs(t->pose.B_rad - want.B_rad) < angle_rad &&
                 std::abs(t->pose.C_rad - want.C_rad) < angle_rad && (t->socket_mm - p.reading.socket_mm).norm() < 1e-6;
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

SsmDemoResult run_ssm_demo(storage::Store& store, const SsmDemoOptions& o, const SsmDemoEvents& events) {
    SsmDemoResult out;
    out.machine = o.registered ? *o.registered : acq::seed_machine(o.machine);
    if (!o.registered || o.tolerances.any()) out.machine.tolerances = o.tolerances;
    acq::PlanSpec spec = o.plan.value_or(acq::default_plan(out.machine));
    spec.answers.operator_name = "demo";
    out.plan = acq::make_plan(out.machine, spec);
    const acq::Plan& plan = out.plan;

    device::EmulatorConfig cfg;
    cfg.seed = o.seed;
    cfg.instrument.calibrated_length_mm = spec.bar_length_mm;
    cfg.instrument.noise_um = 0.1;
    // A serial of this process's own: demos running side by side each reconnect to their own emulator
    // (a pty name can be reused by another one's after a simulated disconnect).
    cfg.instrument.serial = "EMU" + std::to_string(10000 + ::getpid() % 90000);
    cfg.machine.geometry = out.machine.geometry;
    cfg.machine.errors = acq::demo_errors(out.machine.geometry.type);
    cfg.machine.socket_mm = plan.points.front().socket_mm;
    cfg.machine.start = plan.points.front().pose;
    cfg.faults = o.faults;
    PtyEmulator emulator(cfg);
    emulator.emulator().machine().keep_history();  // for the truth check of every stored point

    storage::NewSession ns;
    ns.machine = out.machine.geometry;
    ns.machine_asset = o.machine_asset;
    ns.source = storage::SessionSource::emulator;
    ns.operator_name = "demo";
    ns.procedure = "ssm-two-step";
    ns.notes = o.notes;
    storage::Instrument inst;
    inst.model = cfg.instrument.model;
    inst.serial = cfg.instrument.serial;
    inst.firmware = cfg.instrument.firmware;
    inst.calibrated_length_mm = cfg.instrument.calibrated_length_mm;
    ns.instrument = inst;
    const std::int64_t id = store.create_session(ns);
    out.session_id = id;
    store.start_session(id);
    store_plan(store, id, plan);
    if (events.started) events.started(id, plan, emulator.path());

    DeviceSource source([&emulator] { return device::open_transport("serial:" + emulator.path()); });
    StoreSink sink(store, id, plan);
    EmulatedOperator op(plan, emulator.emulator().machine(), cfg.faults);
    op.on_progress = events.progress;
    op.on_message = events.message;
    std::optional<FrontAtMachine> front;
    if (o.front) front.emplace(*o.front, op);
    acq::SessionOptions so;
    so.stop = o.stop;
    acq::Session session(plan, source, sink, front ? static_cast<acq::Operator&>(*front) : op, so);
    out.summary = session.run();
    sink.finish(out.summary);
    store_bar_resolution(store, id, source, 0);
    emulator.halt();  // the emulator's state is read without racing its thread from here on
    out.check = check_against_truth(store, id, emulator.emulator());
    const auto& ec = emulator.emulator().counters();
    out.dropped_frames = ec.dropped_frames;
    out.replayed_frames = ec.replayed_frames;
    out.corrupted_bytes = ec.corrupted_bytes;
    const TruthCheck& tc = out.check;
    if (out.summary.final_state != acq::State::Done) {
        // An unfinished session must not hide a wrong point either. Its end is told as stored.
        std::string truth = "; its " + std::to_string(tc.points) + " stored points checked against the truth: ";
        truth += tc.wrong_pose == 0
                     ? "all at their pose"
                     : std::to_string(tc.wrong_pose) + " away from their pose (first: " + tc.first_wrong + ")";
        throw Error(ErrorCategory::failed, "demo session " + std::to_string(id) + " ended " +
                                               std::string(storage::to_string(store.session(id).state)) + ": " +
                                               out.summary.reason + truth);
    }
    if (tc.wrong_pose > 0 || tc.stored_twice > 0)
        throw Error(ErrorCategory::failed, "demo session " + std::to_string(id) + ": " + std::to_string(tc.wrong_pose) +
                                               " points stored away from their pose (first: " + tc.first_wrong + "), " +
                                               std::to_string(tc.stored_twice) + " samples stored twice");

    out.truth = acq::true_values(plan, cfg.machine.errors);
    for (const auto& r : store.results(id)) {
        if (r.kind != acq::kSsmResultKind) continue;
        LocationVsTruth l;
        l.measured = acq::location_from_json(r.payload_json);
        const acq::TrueTest& t = out.truth.at(static_cast<std::size_t>(l.measured.test));
        l.true_mm = l.measured.step == 1 ? t.e1_mm : t.e2_mm;
        out.locations.push_back(l);
    }
    return out;
}

}  // namespace ballbar::workflow
