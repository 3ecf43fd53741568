// SPDX-License-Identifier: MIT
#include "ballbar/workflow/gauge_demo.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include "ballbar/acquisition/compute.hpp"
#include "ballbar/acquisition/nc_writer.hpp"
#include "ballbar/acquisition/result_codec.hpp"
#include "ballbar/device/gauge_emulator.hpp"
#include "ballbar/device/sim_machine.hpp"
#include "ballbar/workflow/error.hpp"
#include "ballbar/workflow/gauge_source.hpp"
#include "ballbar/workflow/session_io.hpp"

namespace ballbar::workflow {
namespace {

namespace acq = ballbar::acquisition;
namespace ba = ballbar::analysis;
namespace gg = ballbar::device::gauge;

/// Answers yes; moves the bar into the calibrator for the zero and back onto the machine for the
/// set-up; runs the NC program on the simulated machine.
class GaugeDemoOperator : public acq::ScriptedOperator {
  public:
    GaugeDemoOperator(const acq::Plan& plan, device::SimulatedMachine& machine, gg::GaugeEmulator& emu)
        : acq::ScriptedOperator(plan.spec.answers), machine_(machine), emu_(emu) {}
    bool confirm(std::string_view what, std::string_view prompt) override {
        if (what == "reference") emu_.set_in_calibrator(true);
        if (what == "setup") emu_.set_in_calibrator(false);
        return acq::ScriptedOperator::confirm(what, prompt);
    }
    /// The machine runs the program it is given (a first run or a retry) from where it stands now.
    void run_program(const ba::NcProgram& program, std::span<const std::size_t>, bool) override {
        machine_.stop(now_s());
        machine_.run_program(program);
    }
    /// At a program stop the emulated operator does what it says (moves the socket) and presses
    /// cycle start; the rest runs once the machine stands at the stop.
    void program_stop(const acq::ProgramStop& stop) override {
        if (stop.socket_mm) machine_.set_socket_mm(*stop.socket_mm);
        machine_.cycle_start(0);
    }

  private:
    double now_s() const { return static_cast<double>(emu_.now_us()) * 1e-6; }

    device::SimulatedMachine& machine_;
    gg::GaugeEmulator& emu_;
};

}  // namespace

GaugeDemoResult run_gauge_demo(storage::Store& store, const GaugeDemoOptions& o) {
    const acq::MachineFile machine_file = acq::seed_machine(o.machine);
    acq::PlanSpec spec = acq::default_plan(machine_file);
    spec.answers.operator_name = "demo";
    const acq::Plan plan = acq::make_plan(machine_file, spec);

    device::MachineSetup setup;
    setup.geometry = machine_file.geometry;
    setup.errors = acq::demo_errors(o.machine);
    setup.socket_mm = plan.points.front().socket_mm;
    setup.start = plan.points.front().pose;
    device::SimulatedMachine machine(setup);
    const double L = spec.bar_length_mm;

    gg::GaugeEmulatorConfig gc;
    gc.kind = o.kind;
    gc.seed = o.seed;
    gc.rate_hz = o.rate_hz;
    gc.resolution_mm = 0.0001;  // a 0.1 µm gauge: the high-resolution models a ball-bar wants
    gc.noise_um = 0.1;
    gc.serial = "EMU-G" + std::to_string(o.seed);
    // The Sylvac sits reversed on the bar (its reading falls as the bar grows): the sign is configured.
    gc.sign = o.kind == gg::Kind::Sylvac ? -1.0 : 1.0;
    gg::GaugeEmulator emu(
        gc, [&machine, L](double t_s) { return machine.bar_reading_mm(t_s, 20.0) - L; }, true);

    std::unique_ptr<gg::GaugePtyHost> pty;
    if (o.kind != gg::Kind::MitutoyoItn) pty = std::make_unique<gg::GaugePtyHost>(emu);
    std::string uri = std::string(gg::to_string(o.kind)) + ":" + (pty ? pty->path() : gc.serial);
    if (o.kind == gg::Kind::Modbus) uri += "?slave=1&baud=38400";
    gg::BarOnGauge bar;
    bar.calibrated_length_mm = L;
    bar.sign = gc.sign;
    bar.target_rate_hz = o.rate_hz;
    GaugeSource source(
        [&]() -> std::unique_ptr<gg::Gauge> {
            if (o.kind == gg::Kind::MitutoyoItn) return gg::make_itn_gauge(gg::make_emulated_itn_link(emu, gc.serial));
            return gg::open_gauge(uri);
        },
        bar, [&emu] { return emu.now_us(); });

    storage::NewSession ns;
    ns.machine = machine_file.geometry;
    ns.source = storage::SessionSource::emulator;
    ns.operator_name = "demo";
    ns.procedure = "ssm-two-step";
    ns.notes = o.notes;
    storage::Instrument inst;
    inst.model = std::string(gg::to_string(o.kind)) + " gauge (emulated)";
    inst.serial = o.kind == gg::Kind::MitutoyoItn ? gc.serial : "";
    inst.calibrated_length_mm = L;
    ns.instrument = inst;
    GaugeDemoResult out;
    out.machine_name = machine_file.geometry.name;
    out.session = store.create_session(ns);
    const std::int64_t id = out.session;
    store.start_session(id);
    store_plan(store, id, plan);
    if (o.on_started) o.on_started(uri, id, plan);

    StoreSink sink(store, id, plan);
    GaugeDemoOperator op(plan, machine, emu);
    acq::Session session(plan, source, sink, op);
    out.summary = session.run();
    // The gauge's identity, metadata, and its resolution and measured reading rate on every sample.
    store_gauge_instrument(store, id, source, 0, /*keep_instrument=*/true);
    sink.finish(out.summary);
    if (out.summary.final_state != acq::State::Done)
        throw Error(ErrorCategory::failed, "demo session " + std::to_string(id) + " ended " +
                                               std::string(storage::to_string(store.session(id).state)) + ": " +
                                               out.summary.reason);  // as stored (interrupted, aborted, failed)
    out.instrument_json = source.instrument_json();

    const auto truth = acq::true_values(plan, setup.errors);
    for (const auto& r : store.results(id)) {
        if (r.kind != acq::kSsmResultKind) continue;
        const acq::LocationResult l = acq::location_from_json(r.payload_json);
        const auto& t = truth[static_cast<std::size_t>(l.test)];
        GaugeDemoLocation loc{l.test + 1, l.step, l.ssm.exact_mm, l.step == 1 ? t.e1_mm : t.e2_mm};
        out.max_location_error_um =
            std::max(out.max_location_error_um, (loc.measured_mm - loc.true_mm).cwiseAbs().maxCoeff() * 1e3);
        out.locations.push_back(loc);
    }
    for (const auto& r : out.summary.tests) {
        const auto& t = truth[static_cast<std::size_t>(r.test)].result.orientation.exact;
        const auto& m = r.orientation.exact;
        if (!m || !t) continue;
        const double da = std::abs(m->d_alpha_rad - t->d_alpha_rad), db = std::abs(m->d_beta_rad - t->d_beta_rad),
                     dg = std::abs(m->d_gamma_rad - t->d_gamma_rad);
        // Only the angles the test observes.
        const ba::MeasuredAngles angles = acq::measured_angles(o.machine, r.kind);
        const double d = std::max({angles.alpha ? da : 0.0, angles.beta ? db : 0.0, angles.gamma ? dg : 0.0});
        out.max_orientation_error_arcsec = std::max(out.max_orientation_error_arcsec, ba::rad_to_arcsec(d));
        out.orientation.push_back({r.test + 1, r.kind, *m, *t});
    }
    return out;
}

}  // namespace ballbar::workflow
