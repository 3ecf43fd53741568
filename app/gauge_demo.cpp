// SPDX-License-Identifier: MIT
// `ballbar demo --instrument KIND`: the guided two-step SSM procedure on a bar built on an emulated
// digital gauge. The gauge emulator sits on the simulated machine (its displacement follows the
// machine's bar length, SimulatedMachine::bar_reading_mm) and runs on a simulated clock that each
// reading advances by 1/rate, so a 20 readings/s gauge is as slow as it is on a real bar; the serial
// gauges are reached through a pty and the real drivers (libserialport/termios, libmodbus), the USB-ITN
// through its driver over an in-process USB link. Prints measured against true errors.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "ballbar/acquisition/compute.hpp"
#include "ballbar/acquisition/nc_writer.hpp"
#include "ballbar/acquisition/result_codec.hpp"
#include "ballbar/acquisition/session.hpp"
#include "ballbar/device/gauge_emulator.hpp"
#include "ballbar/device/sim_machine.hpp"
#include "ballbar/workflow/gauge_source.hpp"
#include "ballbar/workflow/session_io.hpp"
#include "command.hpp"
#include "gauge_commands.hpp"
#include "json_out.hpp"

namespace ballbar::app {
namespace {

namespace acq = ballbar::acquisition;
namespace ba = ballbar::analysis;
namespace gg = ballbar::device::gauge;
using ojson = nlohmann::ordered_json;

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

int run_gauge_demo(const GaugeDemoOptions& o, const std::string& db_path) {
    const auto kind = gg::parse_kind(o.instrument);
    if (!kind) throw Error(ErrorCategory::bad_input, "--instrument must be sylvac, mitutoyo-itn, digimatic or modbus");
    const auto type = ba::parse_machine_type(o.machine);
    if (!type) throw Error(ErrorCategory::bad_input, "--machine must be RRTTT, TTTRR or RTTTR");
    const acq::MachineFile machine_file = acq::seed_machine(*type);
    acq::PlanSpec spec = acq::default_plan(machine_file);
    spec.answers.operator_name = "demo";
    const acq::Plan plan = acq::make_plan(machine_file, spec);

    device::MachineSetup setup;
    setup.geometry = machine_file.geometry;
    setup.errors = acq::demo_errors(*type);
    setup.socket_mm = plan.points.front().socket_mm;
    setup.start = plan.points.front().pose;
    device::SimulatedMachine machine(setup);
    const double L = spec.bar_length_mm;

    gg::GaugeEmulatorConfig gc;
    gc.kind = *kind;
    gc.seed = o.seed;
    gc.rate_hz = o.rate_hz;
    gc.resolution_mm = 0.0001;  // a 0.1 µm gauge: the high-resolution models a ball-bar wants
    gc.noise_um = 0.1;
    gc.serial = "EMU-G" + std::to_string(o.seed);
    // The Sylvac sits reversed on the bar (its reading falls as the bar grows): the sign is configured.
    gc.sign = *kind == gg::Kind::Sylvac ? -1.0 : 1.0;
    gg::GaugeEmulator emu(
        gc, [&machine, L](double t_s) { return machine.bar_reading_mm(t_s, 20.0) - L; }, true);

    std::unique_ptr<gg::GaugePtyHost> pty;
    if (*kind != gg::Kind::MitutoyoItn) pty = std::make_unique<gg::GaugePtyHost>(emu);
    std::string uri = std::string(gg::to_string(*kind)) + ":" + (pty ? pty->path() : gc.serial);
    if (*kind == gg::Kind::Modbus) uri += "?slave=1&baud=38400";
    gg::BarOnGauge bar;
    bar.calibrated_length_mm = L;
    bar.sign = gc.sign;
    bar.target_rate_hz = o.rate_hz;
    workflow::GaugeSource source(
        [&]() -> std::unique_ptr<gg::Gauge> {
            if (*kind == gg::Kind::MitutoyoItn) return gg::make_itn_gauge(gg::make_emulated_itn_link(emu, gc.serial));
            return gg::open_gauge(uri);
        },
        bar, [&emu] { return emu.now_us(); });

    storage::StoreOptions so;
    so.sync_full = false;
    storage::Store store(db_path, so);
    storage::NewSession ns;
    ns.machine = machine_file.geometry;
    ns.source = storage::SessionSource::emulator;
    ns.operator_name = "demo";
    ns.procedure = "ssm-two-step";
    ns.notes =
        "ballbar demo --instrument " + o.instrument + " --machine " + o.machine + " --seed " + std::to_string(o.seed);
    storage::Instrument inst;
    inst.model = std::string(gg::to_string(*kind)) + " gauge (emulated)";
    inst.serial = *kind == gg::Kind::MitutoyoItn ? gc.serial : "";
    inst.calibrated_length_mm = L;
    ns.instrument = inst;
    const std::int64_t id = store.create_session(ns);
    store.start_session(id);
    workflow::store_plan(store, id, plan);
    if (!o.json)
        std::cout << "ballbar demo: " << o.machine << " (" << machine_file.geometry.name << "), " << plan.points.size()
                  << " points, on an emulated " << o.instrument << " gauge at " << o.rate_hz << " readings/s (" << uri
                  << ")\n";

    workflow::StoreSink sink(store, id, plan);
    GaugeDemoOperator op(plan, machine, emu);
    acq::Session session(plan, source, sink, op);
    const acq::SessionSummary sum = session.run();
    // The gauge's identity, metadata, and its resolution and measured reading rate on every sample.
    workflow::store_gauge_instrument(store, id, source, 0, /*keep_instrument=*/true);
    sink.finish(sum);
    if (sum.final_state != acq::State::Done)
        throw Error(ErrorCategory::failed, "demo session " + std::to_string(id) + " ended " +
                                               std::string(storage::to_string(store.session(id).state)) + ": " +
                                               sum.reason);  // as stored (interrupted, aborted, failed)

    const auto truth = acq::true_values(plan, setup.errors);
    ojson out;
    out["session"] = id;
    out["machine"] = o.machine;
    out["instrument"] = ojson::parse(source.instrument_json());
    out["locations"] = ojson::array();
    out["orientation"] = ojson::array();
    double worst_um = 0, worst_arcsec = 0;
    for (const auto& r : store.results(id)) {
        if (r.kind != acq::kSsmResultKind) continue;
        const acq::LocationResult l = acq::location_from_json(r.payload_json);
        const int test = l.test, step = l.step;
        const ba::Vec3& m = l.ssm.exact_mm;
        const auto& t = truth[static_cast<std::size_t>(test)];
        const ba::Vec3 tr = step == 1 ? t.e1_mm : t.e2_mm;
        worst_um = std::max(worst_um, (m - tr).cwiseAbs().maxCoeff() * 1e3);
        out["locations"].push_back(
            {{"test", test + 1}, {"step", step}, {"e_mm", vec3_json(m)}, {"true_e_mm", vec3_json(tr)}});
    }
    for (const auto& r : sum.tests) {
        const auto& t = truth[static_cast<std::size_t>(r.test)].result.orientation.exact;
        const auto& m = r.orientation.exact;
        if (!m || !t) continue;
        const double da = std::abs(m->d_alpha_rad - t->d_alpha_rad), db = std::abs(m->d_beta_rad - t->d_beta_rad),
                     dg = std::abs(m->d_gamma_rad - t->d_gamma_rad);
        // Only the angles the test observes (as the plain demo prints them).
        const ba::MeasuredAngles angles = acq::measured_angles(*type, r.kind);
        const double d = std::max({angles.alpha ? da : 0.0, angles.beta ? db : 0.0, angles.gamma ? dg : 0.0});
        worst_arcsec = std::max(worst_arcsec, ba::rad_to_arcsec(d));
        ojson oj = {{"test", r.test + 1}, {"kind", std::string(acq::to_string(r.kind))}};
        put_angles(oj, "", "", m, *type, r.kind);
        put_angles(oj, "true_", "", t, *type, r.kind);
        out["orientation"].push_back(std::move(oj));
    }
    out["max_location_error_um"] = worst_um;
    out["max_orientation_error_arcsec"] = worst_arcsec;
    out["samples"] = sum.samples;
    if (o.json) {
        std::cout << out.dump() << std::endl;
    } else {
        std::printf("\nTotal position errors (SSM exact), µm: measured | true\n");
        for (const auto& l : out["locations"]) {
            const auto& m = l["e_mm"];
            const auto& t = l["true_e_mm"];
            std::printf("  test %d step %d   %8.3f %8.3f %8.3f | %8.3f %8.3f %8.3f\n", l["test"].get<int>(),
                        l["step"].get<int>(), 1e3 * m[0].get<double>(), 1e3 * m[1].get<double>(),
                        1e3 * m[2].get<double>(), 1e3 * t[0].get<double>(), 1e3 * t[1].get<double>(),
                        1e3 * t[2].get<double>());
        }
        std::printf("\nLargest difference from the truth: %.3f µm (positions), %.3f\" (orientations).\n", worst_um,
                    worst_arcsec);
        const auto& ij = out["instrument"];
        std::printf("Gauge: %s %s, %.1f readings/s, resolution %.4g µm.\n", ij["maker"].get<std::string>().c_str(),
                    ij["model"].get<std::string>().c_str(), ij["reading_rate_hz"].get<double>(),
                    1e3 * ij["resolution_mm"].get<double>());
        std::printf("Session %lld stored in %s (%zu samples).\n", static_cast<long long>(id), store.path().c_str(),
                    sum.samples);
    }
    return kExitOk;
}

}  // namespace ballbar::app
