// SPDX-License-Identifier: MIT
// The emulator: determinism, physics (the bar reads the analysis kinematics), protocol behaviour and
// fault injection, driven through the real driver over the in-process pipe.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <vector>

#include "ballbar/analysis/kinematics.hpp"
#include "ballbar/device/emulator.hpp"
#include "ballbar/device/instrument.hpp"
#include "ballbar/device/pipe.hpp"
#include "ballbar/device/uri.hpp"

using namespace ballbar;
using namespace ballbar::device;
using namespace std::chrono_literals;

namespace {

EmulatorConfig quiet_config() {
    EmulatorConfig c;
    c.seed = 42;
    c.instrument.noise_um = 0;
    c.instrument.temp_drift_C_per_h = 0;
    c.instrument.temp_ripple_C = 0;
    c.instrument.temp_start_C = 20.0;
    return c;
}

std::vector<analysis::BarSample> stream_for(Instrument& inst, std::size_t wanted) {
    std::vector<analysis::BarSample> out(wanted);
    std::size_t have = 0;
    for (int i = 0; i < 100000 && have < wanted; ++i) {
        inst.poll(10ms);
        have += inst.read_samples(std::span(out).subspan(have));
    }
    out.resize(have);
    return out;
}

std::unique_ptr<Instrument> connect(Emulator& emu, InstrumentOptions opt = {}) {
    return std::make_unique<Instrument>(std::make_unique<PipeTransport>(emu), opt);
}

}  // namespace

TEST(Emulator, IdentifyStatusConfigureOverThePipe) {
    auto cfg = quiet_config();
    cfg.instrument.serial = "EMU12345";
    Emulator emu(cfg);
    auto inst = connect(emu);
    const auto& info = inst->identify();
    EXPECT_EQ(info.model, "BB-1E");
    EXPECT_EQ(info.serial, "EMU12345");
    EXPECT_EQ(info.protocol_version, 1);
    EXPECT_DOUBLE_EQ(info.calibrated_length_mm, 150.0);
    EXPECT_DOUBLE_EQ(info.resolution_um, 0.1);
    EXPECT_DOUBLE_EQ(info.range_mm, 1.0);
    inst->configure(2000, 4);
    const auto st = inst->status();
    EXPECT_EQ(st.sample_rate_hz, 2000);
    EXPECT_EQ(st.averaging, 4);
    EXPECT_FALSE(st.streaming);
    EXPECT_FALSE(st.referenced);
    EXPECT_NEAR(st.bar_temp_C, 20.0, 0.01);
    EXPECT_GT(st.battery_pct, 90);
    EXPECT_THROW(inst->configure(6000, 1), std::invalid_argument);
    inst->set_reference();
    EXPECT_TRUE(inst->status().referenced);
    emu.advance_to(5000);
    EXPECT_GE(inst->heartbeat(), 5000u);
}

TEST(Emulator, RefusesWithErrorReplies) {
    Emulator emu(quiet_config());
    auto inst = connect(emu);
    inst->start_streaming();
    try {
        inst->configure(100, 1);
        FAIL() << "configure while streaming must be refused";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::Protocol);
        EXPECT_NE(std::string(e.what()).find("busy"), std::string::npos) << e.what();
    }
    EXPECT_THROW(inst->set_reference(), DeviceError);
    inst->stop_streaming();
    inst->configure(100, 1);
}

TEST(Emulator, StreamsAtTheConfiguredRateWithContiguousSequence) {
    Emulator emu(quiet_config());
    auto inst = connect(emu);
    inst->identify();
    inst->configure(1000, 1);
    inst->start_streaming();
    const auto s = stream_for(*inst, 5000);
    inst->stop_streaming();
    ASSERT_EQ(s.size(), 5000u);
    for (std::size_t i = 0; i < s.size(); ++i) {
        ASSERT_EQ(s[i].seq, i);
        if (i > 0) {
            ASSERT_EQ(s[i].device_time_us - s[i - 1].device_time_us, 1000u);
        }
        ASSERT_EQ(s[i].flags & kSampleAfterGap, 0);
        ASSERT_NE(s[i].flags & analysis::kSampleNotReferenced, 0);
    }
    EXPECT_EQ(inst->stats().lost_frames, 0u);
    EXPECT_EQ(inst->stats().invalid_frames, 0u);
    // Unreferenced: the transducer's zero error shows (23.7 µm by default, nominal machine: length = 150).
    EXPECT_NEAR(s[0].displacement_nm, 23700, 100);
}

TEST(Emulator, BarReadsTheActualKinematics) {
    auto cfg = quiet_config();
    cfg.machine.geometry.type = analysis::MachineType::TTTRR;
    cfg.machine.errors[analysis::Param::X0C] = 0.020;
    cfg.machine.errors[analysis::Param::Y0C] = -0.013;
    cfg.machine.errors[analysis::Param::C_zero] = analysis::deg_to_rad(0.01);
    cfg.machine.errors[analysis::Param::EXX] = 50e-6;
    cfg.machine.errors[analysis::Param::bar_length] = 0.004;
    cfg.machine.errors[analysis::Param::bar_kappa] = 11.5e-6;
    cfg.machine.errors[analysis::Param::spindle_growth] = 0.036;  // mm/h
    cfg.machine.socket_offset_mm = analysis::Vec3(0.01, -0.02, 0.005);
    cfg.instrument.temp_start_C = 22.0;
    Emulator emu(cfg);
    auto inst = connect(emu);
    inst->identify();
    inst->set_reference();
    // Circle in C with the tool following the nominal socket: the bar sees the errors only.
    const auto& setup = emu.machine().setup();
    analysis::Pose p = setup.start;
    p.C_rad = analysis::deg_to_rad(90);
    const analysis::Vec3 s = analysis::nominal_table_ball(setup.geometry, p, setup.socket_mm);
    p.X_mm = s.x();
    p.Y_mm = s.y();
    // In 1° steps: a straight move between far points of the circle would leave the ±1 mm range.
    for (int deg = 1; deg <= 90; ++deg) {
        analysis::Pose q = setup.start;
        q.C_rad = analysis::deg_to_rad(deg);
        const analysis::Vec3 sq = analysis::nominal_table_ball(setup.geometry, q, setup.socket_mm);
        q.X_mm = sq.x();
        q.Y_mm = sq.y();
        emu.machine().move_to(q, 2000);
    }
    EXPECT_NEAR(emu.machine().motion_end_s(), 90 * 100 * analysis::deg_to_rad(1) / 2000 * 60, 0.5);
    inst->start_streaming();
    const auto samples = stream_for(*inst, 8000);
    ASSERT_EQ(samples.size(), 8000u);
    EXPECT_TRUE(emu.machine().idle_at(8.0));
    double max_dev = 0;
    for (const auto& smp : samples) {
        const double t_s = static_cast<double>(smp.device_time_us) * 1e-6;
        const double expected = emu.machine().bar_reading_mm(t_s, smp.bar_temp_C);
        // Quantised to 0.1 µm; the machine was sampled at the sample's own time.
        max_dev = std::max(max_dev, std::abs(smp.length_mm(150.0) - expected));
        ASSERT_EQ(smp.flags & (analysis::kSampleNotReferenced | analysis::kSampleOutOfRange), 0);
    }
    EXPECT_LT(max_dev, 0.06e-3);
    // And that truth is the analysis model's predicted reading.
    const auto pose = emu.machine().pose_at(8.0);
    EXPECT_NEAR(
        emu.machine().bar_reading_mm(8.0, 22.0),
        analysis::predicted_reading(setup.geometry, setup.errors, pose, emu.machine().actual_socket_mm(), {8.0, 22.0}),
        1e-12);
}

TEST(Emulator, SameSeedSameBytesDifferentSeedDifferentNoise) {
    auto run = [](std::uint64_t seed) {
        auto cfg = quiet_config();
        cfg.seed = seed;
        cfg.instrument.noise_um = 0.5;
        Emulator emu(cfg);
        auto inst = connect(emu);
        inst->start_streaming();
        auto s = stream_for(*inst, 2000);
        std::vector<std::int32_t> d;
        for (const auto& x : s) d.push_back(x.displacement_nm);
        return d;
    };
    const auto a = run(7), b = run(7), c = run(8);
    ASSERT_EQ(a.size(), 2000u);
    EXPECT_EQ(a, b);
    EXPECT_NE(a, c);
    // The noise has about the configured spread (0.5 µm).
    const double mean = std::accumulate(a.begin(), a.end(), 0.0) / static_cast<double>(a.size());
    double var = 0;
    for (auto v : a) var += (v - mean) * (v - mean);
    EXPECT_NEAR(std::sqrt(var / static_cast<double>(a.size())), 500.0, 50.0);
}

TEST(Emulator, OutOfRangeIsClampedAndFlagged) {
    auto cfg = quiet_config();
    cfg.machine.start.Z_mm = 151.5;  // 1.5 mm long
    Emulator emu(cfg);
    auto inst = connect(emu);
    inst->identify();
    inst->start_streaming();
    const auto s = stream_for(*inst, 100);
    ASSERT_EQ(s.size(), 100u);
    for (const auto& x : s) {
        EXPECT_EQ(x.displacement_nm, 1'000'000);
        EXPECT_NE(x.flags & analysis::kSampleOutOfRange, 0);
    }
}

TEST(Emulator, MachineExecutesNcProgram) {
    auto cfg = quiet_config();
    cfg.program = NcSource{"G90\nG1 X110 F600\nG4 P1000\nG0 X100\n", analysis::NcDialect::Fanuc, true, {}};
    Emulator emu(cfg);
    auto& m = emu.machine();
    EXPECT_NEAR(m.pose_at(0.5).X_mm, 105.0, 1e-9);  // 10 mm at 600 mm/min takes 1 s
    EXPECT_NEAR(m.pose_at(1.5).X_mm, 110.0, 1e-9);  // dwell
    EXPECT_FALSE(m.idle_at(2.0));
    EXPECT_NEAR(m.pose_at(3.0).X_mm, 100.0, 1e-9);
    EXPECT_TRUE(m.idle_at(3.0));
    EXPECT_NEAR(m.true_distance_mm(3.0), 150.0, 1e-9);
}

/// The truth a campaign checks stored points against: where the machine stood at a past time, also in
/// a move cut short by a stop; and a socket the operator moves at a program stop moves when the
/// machine stands there, not while the motion queued before it still runs.
TEST(Emulator, MachineRemembersWhereItStoodAndWhenTheSocketMoved) {
    auto cfg = quiet_config();
    cfg.machine.socket_mm = analysis::Vec3(100, 0, 0);
    Emulator emu(cfg);
    auto& m = emu.machine();
    EXPECT_FALSE(m.truth_at(0.0)) << "no history asked for";
    m.keep_history();
    const analysis::Pose start = cfg.machine.start;
    analysis::Pose far = start;
    far.X_mm += 10;
    m.move_to(far, 600);                         // 1 s
    m.dwell(1);                                  // until 2 s
    m.set_socket_mm(analysis::Vec3(120, 0, 0));  // the operator, at the stop after the dwell
    EXPECT_NEAR(m.actual_socket_mm().x(), 100, 1e-12) << "not while the machine still moves";
    EXPECT_NEAR(m.bar_reading_mm(1.5, 20.0) - m.bar_reading_mm(1.9, 20.0), 0, 1e-12);
    analysis::Pose back = far;
    back.X_mm -= 20;
    m.move_to(back, 600);  // 2 s: from 2 s to 4 s, stopped at 3 s
    m.stop(3.0);
    m.pose_at(5.0);
    ASSERT_TRUE(m.truth_at(0.5));
    EXPECT_NEAR(m.truth_at(0.5)->pose.X_mm, start.X_mm + 5, 1e-9);
    EXPECT_NEAR(m.truth_at(1.5)->pose.X_mm, far.X_mm, 1e-9);
    EXPECT_NEAR(m.truth_at(1.5)->socket_mm.x(), 100, 1e-12);
    EXPECT_NEAR(m.truth_at(2.5)->socket_mm.x(), 120, 1e-12);
    EXPECT_NEAR(m.truth_at(2.5)->pose.X_mm, far.X_mm - 5, 1e-9);
    EXPECT_NEAR(m.truth_at(4.5)->pose.X_mm, far.X_mm - 10, 1e-9) << "stood where the stop left it";
    EXPECT_FALSE(m.truth_at(6.0)) << "a time the machine has not reached";
}

TEST(Faults, DroppedFramesAreCountedNeverHidden) {
    auto cfg = quiet_config();
    cfg.faults.drop_frame_probability = 0.1;
    Emulator emu(cfg);
    auto inst = connect(emu);
    inst->start_streaming();
    const auto s = stream_for(*inst, 10000);
    ASSERT_EQ(s.size(), 10000u);
    const auto& st = inst->stats();
    EXPECT_GT(st.lost_frames, 0u);
    // Every dropped frame the host could see (before the last received one) is counted.
    EXPECT_LE(st.lost_frames, emu.counters().dropped_frames);
    EXPECT_GE(st.lost_frames + 2, emu.counters().dropped_frames);
    std::size_t marked = 0;
    for (std::size_t i = 1; i < s.size(); ++i) {
        const bool jump = s[i].device_time_us - s[i - 1].device_time_us != 1000;
        const bool flagged = (s[i].flags & kSampleAfterGap) != 0;
        ASSERT_EQ(jump, flagged) << i;  // a gap in time is flagged, and only then
        marked += flagged;
        ASSERT_EQ(s[i].seq, i);  // host sequence stays contiguous
    }
    EXPECT_EQ(marked, st.gaps);
}

TEST(Faults, CorruptBytesAreRejectedAndCounted) {
    auto cfg = quiet_config();
    cfg.faults.corrupt_byte_probability = 0.001;
    Emulator emu(cfg);
    auto inst = connect(emu);
    inst->start_streaming();
    const auto s = stream_for(*inst, 20000);
    ASSERT_GT(s.size(), 15000u);
    EXPECT_GT(emu.counters().corrupted_bytes, 0u);
    EXPECT_GT(inst->stats().invalid_frames, 0u);
    EXPECT_GT(inst->stats().lost_frames, 0u);
    // No corrupted value got through: with no noise and a standing machine every sample is the same.
    for (const auto& x : s) ASSERT_EQ(x.displacement_nm, s[0].displacement_nm);
}

TEST(Faults, StallHoldsOutputThenDeliversItAll) {
    auto cfg = quiet_config();
    cfg.faults.stall_at_s = 1.0;
    cfg.faults.stall_s = 2.0;
    Emulator emu(cfg);
    auto inst = connect(emu);
    inst->start_streaming();
    const auto s = stream_for(*inst, 5000);
    ASSERT_EQ(s.size(), 5000u);
    EXPECT_EQ(inst->stats().lost_frames, 0u);
    // A request during the stall times out (the device is silent) ...
    Emulator emu2(cfg);
    auto inst2 = connect(emu2, {.reply_timeout = 200ms, .attempts = 1});
    emu2.advance_to(1'100'000);
    EXPECT_THROW(
        {
            try {
                inst2->identify();
            } catch (const DeviceError& e) {
                EXPECT_EQ(e.kind(), DeviceErrorKind::Timeout);
                throw;
            }
        },
        DeviceError);
    // ... and the device answers after it.
    emu2.advance_to(3'100'000);
    inst2->identify();
}

TEST(Faults, SlowRepliesWithinTimeoutAndRetriesBeyond) {
    auto cfg = quiet_config();
    cfg.faults.reply_delay_ms = 300;
    Emulator emu(cfg);
    auto inst = connect(emu, {.reply_timeout = 500ms, .attempts = 1});
    inst->identify();
    emu.faults().reply_delay_ms = 700;
    try {
        inst->status();
        FAIL();
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::Timeout);
    }
    // The late reply is recognised as stale, not taken for the next answer.
    inst->poll(300ms);
    EXPECT_EQ(inst->stats().stale_replies, 1u);
    emu.faults().reply_delay_ms = 0;
    const auto st = inst->status();
    EXPECT_FALSE(st.streaming);
    EXPECT_GE(inst->stats().stale_replies, 1u);
}

TEST(Faults, DisconnectMidStreamAndComeBack) {
    auto cfg = quiet_config();
    cfg.faults.disconnect_at_s = 2.0;
    cfg.faults.disconnect_s = 1.0;
    Emulator emu(cfg);
    auto inst = connect(emu);
    inst->identify();
    inst->start_streaming();
    std::vector<analysis::BarSample> buf(4096);
    std::size_t got = 0;
    try {
        for (int i = 0; i < 10000; ++i) {
            inst->poll(10ms);
            got += inst->read_samples(buf);
        }
        FAIL() << "the disconnect was not reported";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::Disconnected);
    }
    EXPECT_NEAR(static_cast<double>(got), 2000.0, 30.0);
    EXPECT_FALSE(inst->streaming());
    // Still gone: a new connection is refused until the device is back.
    auto again = connect(emu);
    EXPECT_THROW(again->identify(), DeviceError);
    emu.advance_to(3'000'001);
    EXPECT_TRUE(emu.connected());
    EXPECT_EQ(emu.connection_epoch(), 1u);
    auto inst2 = connect(emu);
    inst2->identify();
    EXPECT_FALSE(inst2->status().streaming);
    inst2->start_streaming();
    EXPECT_EQ(stream_for(*inst2, 1000).size(), 1000u);
    EXPECT_EQ(inst2->stats().lost_frames, 0u);
}

TEST(Faults, WatchdogStopsAnAbandonedStream) {
    auto cfg = quiet_config();
    cfg.instrument.watchdog_s = 2.0;
    Emulator emu(cfg);
    auto inst = connect(emu);
    inst->start_streaming();
    emu.advance_to(emu.now_us() + 1'000'000);
    EXPECT_TRUE(emu.streaming());
    emu.advance_to(emu.now_us() + 1'500'000);
    EXPECT_FALSE(emu.streaming());
}

TEST(Driver, QueueOverflowIsCountedAndMarked) {
    Emulator emu(quiet_config());
    InstrumentOptions opt;
    opt.queue_capacity = 256;
    auto inst = connect(emu, opt);
    inst->start_streaming();
    while (emu.now_us() < 1'000'000) inst->poll(10ms);  // ~1000 samples, nobody reads
    EXPECT_EQ(inst->queue().size(), 256u);
    EXPECT_GT(inst->stats().queue_drops, 500u);
    std::vector<analysis::BarSample> buf(300);
    EXPECT_EQ(inst->read_samples(buf), 256u);
    for (int i = 0; i < 5; ++i) inst->poll(10ms);
    const auto n = inst->read_samples(buf);
    ASSERT_GT(n, 0u);
    EXPECT_NE(buf[0].flags & kSampleAfterGap, 0);
    EXPECT_EQ(buf[0].seq, 256u);  // host sequence stays contiguous; the loss is in the flag and stats
}

/// "time": "simulated" puts an `emulator:CONFIG` link on the emulator's own clock: a minute of streaming
/// takes the CPU's time. The default follows the wall clock; anything else is refused naming the key.
TEST(Config, SimulatedTimeMakesAnInProcessLinkRunAsFastAsItIsRead) {
    EXPECT_FALSE(parse_emulator_config("{}").simulated_time);
    EXPECT_FALSE(parse_emulator_config(R"({"time": "real"})").simulated_time);
    EXPECT_TRUE(parse_emulator_config(R"({"time": "simulated"})").simulated_time);
    for (const char* bad : {R"({"time": "fast"})", R"({"time": 1})"}) {
        try {
            (void)parse_emulator_config(bad);
            ADD_FAILURE() << "accepted " << bad;
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find("time: must be"), std::string::npos) << e.what();
        }
    }
    char tmpl[] = "/tmp/ballbar-time-XXXXXX";
    const std::string dir = ::mkdtemp(tmpl);
    const std::string cfg = dir + "/sim.json";
    std::ofstream(cfg) << R"({"time": "simulated", "instrument": {"sample_rate_hz": 1000}})";
    Instrument inst(open_transport("emulator:" + cfg));
    (void)inst.identify();
    inst.start_streaming();
    const auto t0 = std::chrono::steady_clock::now();
    std::size_t samples = 0;
    std::vector<analysis::BarSample> batch(4096);
    while (samples < 60000) {  // a minute of the bar's samples
        inst.poll(std::chrono::milliseconds(200));
        samples += inst.read_samples(batch);
        ASSERT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(20)) << "not the wall clock's minute";
    }
    std::filesystem::remove_all(dir);
}

TEST(Config, ParsesEverySectionAndRejectsMistakes) {
    const auto c = parse_emulator_config(R"({
        "seed": 9,
        "instrument": {"serial": "BB0042", "calibrated_length_mm": 100, "noise_um": 0.1, "sample_rate_hz": 2000},
        "machine": {"type": "RRTTT", "tool_ball_mm": [0, 0, -150], "socket_mm": [0, 0, -350],
                    "start": {"X_mm": 0, "Y_mm": 0, "Z_mm": 0, "A_deg": 10},
                    "errors": {"X0B": 0.01, "A_zero_deg": 0.02, "Z0A_um": 5}},
        "program": {"text": "G1 A20 F100\nG4 P500\n"},
        "faults": {"drop_frame_probability": 0.01, "disconnect_at_s": 5, "disconnect_s": 1}
    })");
    EXPECT_EQ(c.seed, 9u);
    EXPECT_EQ(c.instrument.serial, "BB0042");
    EXPECT_EQ(c.instrument.sample_rate_hz, 2000);
    EXPECT_EQ(c.machine.geometry.type, analysis::MachineType::RRTTT);
    EXPECT_DOUBLE_EQ(c.machine.errors[analysis::Param::X0B], 0.01);
    EXPECT_NEAR(c.machine.errors[analysis::Param::A_zero], analysis::deg_to_rad(0.02), 1e-15);
    EXPECT_NEAR(c.machine.errors[analysis::Param::Z0A], 0.005, 1e-15);
    EXPECT_NEAR(c.machine.start.A_rad, analysis::deg_to_rad(10), 1e-15);
    ASSERT_TRUE(c.program.has_value());
    EXPECT_DOUBLE_EQ(c.faults.disconnect_at_s, 5.0);

    auto fails_naming = [](const char* json, const char* key) {
        try {
            parse_emulator_config(json);
            ADD_FAILURE() << "accepted " << json;
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
        }
    };
    fails_naming(R"({"instrument": {"sample_rate_hz": 6000}})", "sample_rate_hz");
    fails_naming(R"({"machine": {"errors": {"EXX_ppm": 1}}})", "EXX_ppm");
    fails_naming(R"({"machine": {"errors": {"X0C_deg": 1}}})", "X0C_deg");
    fails_naming(R"({"machine": {"type": "XYZ"}})", "type");
    fails_naming(R"({"faults": {"drop_frame_probability": 2}})", "drop_frame_probability");
    fails_naming(R"({"instrumnet": {}})", "instrumnet");
    fails_naming(R"({"program": {"text": "G2 X1\n"}})", "line 1");
    fails_naming(R"({)", "not valid JSON");
}

TEST(Driver, FramesOfAnAbandonedSessionAreNotCountedAsLost) {
    Emulator emu(quiet_config());
    {
        auto first = connect(emu);
        first->start_streaming();
        ASSERT_EQ(stream_for(*first, 1000).size(), 1000u);
    }  // gone without Stop: the device keeps streaming into the link
    emu.advance_to(emu.now_us() + 200'000);
    auto second = connect(emu);
    second->identify();
    EXPECT_GT(second->stats().stale_frames, 0u);
    EXPECT_TRUE(second->status().streaming);
    second->start_streaming();  // restarts the stream from sequence 0
    ASSERT_EQ(stream_for(*second, 3000).size(), 3000u);
    EXPECT_EQ(second->stats().lost_frames, 0u);
    EXPECT_EQ(second->stats().gaps, 0u);
}
