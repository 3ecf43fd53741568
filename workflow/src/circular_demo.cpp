// SPDX-License-Identifier: MIT
#include "ballbar/workflow/circular_demo.hpp"

#include <unistd.h>

#include <cmath>

#include "ballbar/acquisition/circle_program.hpp"
#include "ballbar/device/uri.hpp"
#include "ballbar/workflow/circular_measure.hpp"
#include "ballbar/workflow/pty_emulator.hpp"

namespace ballbar::workflow {

namespace circ = analysis::circular;

device::ContinuousErrors circular_demo_errors() {
    device::ContinuousErrors e;
    const double lag[3] = {8.0, 5.0, 6.5}, backlash[3] = {3.0, -2.0, 2.5}, spike[3] = {2.0, 1.5, 1.8},
                 scale[3] = {15.0, -10.0, 8.0}, cyclic[3] = {0.8, 0.0, 0.7}, pitch[3] = {6.0, 0.0, 5.0};
    for (std::size_t a = 0; a < 3; ++a) {
        e.axis[a].servo_lag_ms = lag[a];
        e.axis[a].backlash_um = backlash[a];
        e.axis[a].reversal_spike_um = spike[a];
        e.axis[a].scale_ppm = scale[a];
        e.axis[a].cyclic_um = cyclic[a];
        e.axis[a].cyclic_pitch_mm = pitch[a];
        e.axis[a].cyclic_phase_deg = 30.0 * static_cast<double>(a);
    }
    e.squareness_um_per_m = {25.0, -20.0, 30.0};
    e.straightness_um_per_m2[0][1] = 150.0;   // X bows in Y
    e.straightness_um_per_m2[1][2] = -120.0;  // Y bows in Z
    e.straightness_um_per_m2[2][0] = 100.0;   // Z bows in X
    e.vibration_um = 0.6;
    e.vibration_hz = 31.0;
    return e;
}

CircularDemoResult run_circular_demo(storage::Store& store, const CircularDemoOptions& o, acquisition::Operator& op) {
    const circ::TestSpec& test = o.test;
    const auto dialect = analysis::NcDialect::Fanuc;
    const double dwell_s = 1.0;

    device::EmulatorConfig cfg;
    cfg.seed = o.seed;
    cfg.instrument.calibrated_length_mm = test.radius_mm;
    cfg.instrument.noise_um = 0.15;
    cfg.instrument.serial = "EMU" + std::to_string(10000 + ::getpid() % 90000);
    cfg.continuous = circular_demo_errors();
    cfg.machine.socket_offset_mm = analysis::Vec3(0.012, -0.008, 0.015);
    // The stand starts at the first run's feed-in point, R + feed-in out along its start angle.
    const auto ax = circ::plane_axis_index(test.plane);
    analysis::Vec3 start(test.centre_mm[0], test.centre_mm[1], test.centre_mm[2]);
    const double a0 = analysis::deg_to_rad(test.runs.front().start_deg);
    start[ax[0]] += (test.radius_mm + test.feed_in_mm) * std::cos(a0);
    start[ax[1]] += (test.radius_mm + test.feed_in_mm) * std::sin(a0);
    cfg.machine.start = {start.x(), start.y(), start.z(), 0, 0, 0};
    cfg.program = device::NcSource{acquisition::circular_program(test, dialect, dwell_s), dialect, false, ""};
    cfg.faults = o.faults;
    PtyEmulator emulator(cfg);

    CircularDemoResult out;
    out.session =
        create_circular_session(store, test, dialect, dwell_s, storage::SessionSource::emulator, "demo", o.notes);
    if (o.on_started) o.on_started(emulator.path(), out.session);
    PreparedCircular prepared;
    prepared.session = out.session;
    prepared.test = test;
    prepared.dialect = dialect;
    prepared.dwell_s = dwell_s;
    CircularMeasureOptions measure;
    measure.device_uri = "emulator:";
    measure.stop = o.stop;
    measure.open_transport = [&emulator] { return device::open_transport("serial:" + emulator.path()); };
    const CircularMeasureResult run = measure_circular(store, prepared, op, measure);
    emulator.halt();
    throw_unless_completed(run.summary, out.session, "");  // a demo is run again, not resumed
    out.summary = run.summary;
    out.result = run.stored->result;
    out.checks =
        device::compare_with_truth(out.result, emulator.emulator().continuous()->truth(test.plane, test.radius_mm));
    out.pass = true;
    for (const auto& c : out.checks) out.pass = out.pass && c.pass;
    out.dropped_frames = emulator.emulator().counters().dropped_frames;
    out.replayed_frames = emulator.emulator().counters().replayed_frames;
    return out;
}

}  // namespace ballbar::workflow
