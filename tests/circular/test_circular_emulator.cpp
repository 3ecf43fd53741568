// SPDX-License-Identifier: MIT
// The emulator's continuous motion (device/continuous_machine.*): the part program's path, and each
// effect of trace.md injected alone and recovered, with its sign, by the analysis from samples that went
// through the real codec and driver over the in-process pipe (simulated time).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "ballbar/acquisition/circle_program.hpp"
#include "ballbar/analysis/circular.hpp"
#include "ballbar/device/continuous_machine.hpp"
#include "ballbar/device/emulator.hpp"
#include "ballbar/device/instrument.hpp"
#include "ballbar/device/pipe.hpp"

using namespace ballbar;
using namespace ballbar::device;
using namespace std::chrono_literals;
namespace circ = ballbar::analysis::circular;

namespace {

circ::TestSpec test_spec(circ::Plane plane, bool full, double radius = 100, double feed = 2000) {
    circ::TestSpec t;
    t.plane = plane;
    t.radius_mm = radius;
    t.feed_mm_min = feed;
    t.feed_in_mm = 0.8;
    const double over = full ? 45 : 20, arc = full ? 360 : 180, start = full ? 0 : -20;
    t.runs = {{circ::Direction::Ccw, start, over, arc}, {circ::Direction::Cw, start + 2 * over + arc, over, arc}};
    return t;
}

EmulatorConfig config_for(const circ::TestSpec& t, const ContinuousErrors& e, double noise_um = 0.1) {
    EmulatorConfig c;
    c.seed = 7;
    c.instrument.calibrated_length_mm = t.radius_mm;
    c.instrument.noise_um = noise_um;
    c.continuous = e;
    const auto ax = circ::plane_axis_index(t.plane);
    analysis::Vec3 start(t.centre_mm[0], t.centre_mm[1], t.centre_mm[2]);
    const double a = analysis::deg_to_rad(t.runs.front().start_deg);
    start[ax[0]] += (t.radius_mm + t.feed_in_mm) * std::cos(a);
    start[ax[1]] += (t.radius_mm + t.feed_in_mm) * std::sin(a);
    c.machine.start = {start.x(), start.y(), start.z(), 0, 0, 0};
    c.program = NcSource{acquisition::circular_program(t, analysis::NcDialect::Fanuc, 1.0), analysis::NcDialect::Fanuc,
                         false, ""};
    return c;
}

/// Streams the whole program through the driver: Start is the operator's cycle start.
std::vector<circ::TraceSample> record(Emulator& emu) {
    Instrument inst(std::make_unique<PipeTransport>(emu));
    const auto info = inst.identify();
    inst.configure(1000, 1);
    inst.set_reference();
    inst.start_streaming();
    const double end_s = emu.continuous()->program_end_s() + 0.5;
    std::vector<circ::TraceSample> out;
    std::vector<analysis::BarSample> buf(512);
    while (out.empty() || out.back().time_s < end_s) {
        inst.poll(10ms);
        const std::size_t n = inst.read_samples(buf);
        for (std::size_t i = 0; i < n; ++i)
            out.push_back(
                {static_cast<double>(buf[i].device_time_us) * 1e-6, buf[i].length_mm(info.calibrated_length_mm)});
    }
    inst.stop_streaming();
    return out;
}

struct Outcome {
    circ::CircularResult result;
    std::vector<TruthComparison> checks;
};

Outcome measure(const circ::TestSpec& t, const ContinuousErrors& e) {
    Emulator emu(config_for(t, e));
    const auto samples = record(emu);
    Outcome o{circ::analyze_circular(t, samples), {}};
    o.checks = compare_with_truth(o.result, emu.continuous()->truth(t.plane, t.radius_mm));
    return o;
}

ContinuousErrors lagged(double lag_ms = 5) {
    ContinuousErrors e;
    for (auto& a : e.axis) a.servo_lag_ms = lag_ms;
    return e;
}

/// Every diagnostic within the accuracy rule; the injected one with its sign.
void expect_recovered(const Outcome& o, circ::Diag injected, double truth) {
    bool seen = false;
    for (const auto& c : o.checks) {
        EXPECT_TRUE(c.pass) << c.key << ": truth " << c.truth << ", measured "
                            << (c.measured ? std::to_string(*c.measured) : c.note) << ", allowed " << c.allowed;
        if (c.diag == injected) {
            seen = true;
            ASSERT_TRUE(c.measured) << c.key << " not reported: " << c.note;
            EXPECT_EQ(std::signbit(*c.measured), std::signbit(truth)) << c.key << " " << *c.measured;
        }
    }
    EXPECT_TRUE(seen);
}

void one_effect(circ::Diag diag, double truth, const std::function<void(ContinuousErrors&)>& set,
                circ::Plane plane = circ::Plane::XY) {
    ContinuousErrors e = lagged();
    set(e);
    expect_recovered(measure(test_spec(plane, true), e), diag, truth);
}

}  // namespace

TEST(ContinuousMachine, ParsesTheCirclePlanProgramIntoLinesArcsAndDwells) {
    const auto t = test_spec(circ::Plane::ZX, false);
    const std::string text = acquisition::circular_program(t, analysis::NcDialect::LinuxCNC, 1.5);
    const auto path = parse_motion_program(text, analysis::NcDialect::LinuxCNC, {0, 0, 0}, 10000);
    int arcs = 0, dwells = 0;
    double sweep = 0;
    for (const auto& s : path) {
        if (s.kind == PathSegment::Kind::Arc) {
            ++arcs;
            sweep += s.sweep_rad;
            EXPECT_EQ(s.p, 2);  // G18: Z, X
            EXPECT_EQ(s.q, 0);
            EXPECT_NEAR(s.r0, 100.0, 1e-3);
        }
        if (s.kind == PathSegment::Kind::Dwell) {
            ++dwells;
            EXPECT_DOUBLE_EQ(s.duration_s, 1.5);
        }
    }
    EXPECT_EQ(dwells, 3);
    EXPECT_GE(arcs, 6);
    EXPECT_NEAR(sweep, 0.0, 1e-9);  // 220° ccw, then 220° cw
}

TEST(ContinuousMachine, RefusesWordsItCannotRunWithTheLine) {
    try {
        parse_motion_program("G90\nG1 X1 F100\nG2 X2 Y0 R5\n", analysis::NcDialect::Fanuc, {0, 0, 0}, 1000);
        FAIL();
    } catch (const analysis::NcError& e) {
        EXPECT_EQ(e.line(), 3);
    }
    EXPECT_THROW(parse_motion_program("G91 G1 X1 F100\n", analysis::NcDialect::Fanuc, {0, 0, 0}, 1000),
                 analysis::NcError);
    EXPECT_THROW(parse_motion_program("G1 X1\n", analysis::NcDialect::Fanuc, {0, 0, 0}, 1000), analysis::NcError);
}

TEST(ContinuousMachine, FollowsTheCommandThroughItsLagAndStandsAtTheSocketRadius) {
    ContinuousSetup s;
    s.errors = lagged(10);
    s.start_mm = {100.8, 0, 0};
    ContinuousMachine m(s);
    const auto t = test_spec(circ::Plane::XY, true);
    m.run_program(acquisition::circular_program(t, analysis::NcDialect::Fanuc, 1.0), analysis::NcDialect::Fanuc, 2.0);
    EXPECT_NEAR(m.bar_length_mm(2.5), 100.8, 1e-9);  // the dwell at R + feed-in
    const double on_circle = 2.0 + 1.0 + 0.8 / (2000.0 / 60.0) + 1.0;
    EXPECT_NEAR(m.bar_length_mm(on_circle), 100.0, 0.002);  // the lag's radial loss R ω²τ²/2 is tiny
    // On the arc the axis trails the command by about v·τ along the path.
    const auto c = m.commanded_mm(on_circle);
    const auto a = m.actual_mm(on_circle);
    EXPECT_NEAR(std::hypot(c[0] - a[0], c[1] - a[1]), 2000.0 / 60.0 * 0.010, 0.01);
    EXPECT_NEAR(m.program_end_s(),
                2.0 + 2 * (1.0 + 2 * 0.8 / (2000.0 / 60.0) + 450 * M_PI / 180 * 100 / (2000.0 / 60.0)) + 1.0, 0.01);
}

TEST(ContinuousEmulator, BacklashOfXIsRecoveredWithItsSign) {
    one_effect(circ::Diag::BacklashP, 4.0, [](ContinuousErrors& e) { e.axis[0].backlash_um = 4.0; });
}
TEST(ContinuousEmulator, NegativeBacklashOfYIsRecoveredWithItsSign) {
    one_effect(circ::Diag::BacklashQ, -3.0, [](ContinuousErrors& e) { e.axis[1].backlash_um = -3.0; });
}
TEST(ContinuousEmulator, ReversalSpikeOfXIsRecoveredWithItsSign) {
    one_effect(circ::Diag::SpikeP, 3.0, [](ContinuousErrors& e) { e.axis[0].reversal_spike_um = 3.0; });
}
TEST(ContinuousEmulator, ReversalSpikeOfYIsRecoveredWithItsSign) {
    one_effect(circ::Diag::SpikeQ, -2.5, [](ContinuousErrors& e) { e.axis[1].reversal_spike_um = -2.5; });
}
TEST(ContinuousEmulator, SquarenessIsRecoveredWithItsSign) {
    one_effect(circ::Diag::Squareness, -40.0, [](ContinuousErrors& e) { e.squareness_um_per_m[0] = -40.0; });
}
TEST(ContinuousEmulator, ScaleMismatchIsRecoveredWithItsSign) {
    one_effect(circ::Diag::ScaleMismatch, 30.0, [](ContinuousErrors& e) {
        e.axis[0].scale_ppm = 20.0;
        e.axis[1].scale_ppm = -10.0;
    });
}
TEST(ContinuousEmulator, ServoMismatchIsRecoveredWithItsSign) {
    one_effect(circ::Diag::ServoMismatch, -4.0, [](ContinuousErrors& e) {
        e.axis[0].servo_lag_ms = 6.0;
        e.axis[1].servo_lag_ms = 10.0;
    });
}
TEST(ContinuousEmulator, CyclicErrorOfXIsRecoveredWithItsPitch) {
    one_effect(circ::Diag::CyclicP, 1.5, [](ContinuousErrors& e) {
        e.axis[0].cyclic_um = 1.5;
        e.axis[0].cyclic_pitch_mm = 8.0;
    });
}
TEST(ContinuousEmulator, StraightnessOfXIsRecoveredWithItsSign) {
    // k·R² = 250 µm/m² · (0.1 m)² = 2.5 µm
    one_effect(circ::Diag::StraightnessP, 2.5, [](ContinuousErrors& e) { e.straightness_um_per_m2[0][1] = 250.0; });
}
TEST(ContinuousEmulator, StraightnessOfYIsRecoveredWithItsSign) {
    one_effect(circ::Diag::StraightnessQ, -2.0, [](ContinuousErrors& e) { e.straightness_um_per_m2[1][0] = -200.0; });
}
TEST(ContinuousEmulator, VibrationIsRecoveredWithItsFrequency) {
    one_effect(circ::Diag::Vibration, 1.0, [](ContinuousErrors& e) {
        e.vibration_um = 1.0;
        e.vibration_hz = 23.0;
    });
}
TEST(ContinuousEmulator, YzPartialArcRecoversBacklashOfZAndSquareness) {
    ContinuousErrors e = lagged();
    e.axis[2].backlash_um = 3.0;
    e.squareness_um_per_m[1] = 50.0;
    const auto o = measure(test_spec(circ::Plane::YZ, false), e);
    expect_recovered(o, circ::Diag::BacklashQ, 3.0);
    expect_recovered(o, circ::Diag::Squareness, 50.0);
}
TEST(ContinuousEmulator, ZxPartialArcRecoversScaleMismatchAndSpikeOfX) {
    ContinuousErrors e = lagged();
    e.axis[2].scale_ppm = -25.0;        // p = Z
    e.axis[0].reversal_spike_um = 2.0;  // q = X
    const auto o = measure(test_spec(circ::Plane::ZX, false), e);
    expect_recovered(o, circ::Diag::ScaleMismatch, -25.0);
    expect_recovered(o, circ::Diag::SpikeQ, 2.0);
}
