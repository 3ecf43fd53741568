// SPDX-License-Identifier: MIT
// Gauge codecs (need more / valid / invalid), the emulators end to end through the real drivers (serial
// transport over a pty, libmodbus over a pty, the ITN driver over its in-process link), every emulated
// fault, the sampler (zero, sign, inch, rate, resolution, gaps) and the feed limit of a slow gauge.
#include <gtest/gtest.h>

#include <cmath>

#include "ballbar/device/gauge.hpp"
#include "ballbar/device/gauge_emulator.hpp"

namespace ballbar::device::gauge {
namespace {

using namespace std::chrono_literals;

TEST(GaugeCodecs, SylvacNeedsTheCarriageReturn) {
    EXPECT_EQ(decode_sylvac("+001.23").result, Decode::NeedMore);
    const Decoded d = decode_sylvac("+001.234\r+0");
    ASSERT_EQ(d.result, Decode::Valid);
    EXPECT_EQ(d.consumed, 9u);
    EXPECT_DOUBLE_EQ(d.reading.value, 1.234);
    EXPECT_EQ(d.reading.decimals, 3);
    EXPECT_NEAR(d.reading.resolution_mm(), 0.001, 1e-15);
    EXPECT_EQ(decode_sylvac("E1\r").reading.status, ReadingStatus::NotReady);
    EXPECT_EQ(decode_sylvac("E2\r").reading.status, ReadingStatus::OutOfRange);
    EXPECT_EQ(decode_sylvac("MM\r").text, "MM");
    EXPECT_EQ(decode_sylvac("\r").result, Decode::Invalid);
    EXPECT_EQ(decode_sylvac(std::string(kMaxLine + 1, '1')).result, Decode::Invalid);
    EXPECT_EQ(decode_sylvac("+1\x02.0\r").result, Decode::Invalid);
}

TEST(GaugeCodecs, ItnDataAndStatusLines) {
    const Decoded d = decode_itn("01A-0000.123\r");
    ASSERT_EQ(d.result, Decode::Valid);
    EXPECT_DOUBLE_EQ(d.reading.value, -0.123);
    EXPECT_EQ(decode_itn("01A+0000.1").result, Decode::NeedMore);
    EXPECT_EQ(decode_itn("918\r").reading.status, ReadingStatus::NotReady);
    EXPECT_EQ(decode_itn("911\r").reading.status, ReadingStatus::OutOfRange);
    EXPECT_EQ(decode_itn("01A+00000123\r").result, Decode::Invalid);  // no decimal point
    EXPECT_EQ(decode_itn("01A+000.123\r").result, Decode::Invalid);   // seven characters
}

// Found by fuzz_gauge_replies: a status line with a code past int ("9" and eleven digits, "E" and
// twelve) converted a double that does not fit into int (undefined behaviour). It is a gauge error.
TEST(GaugeCodecs, StatusCodesPastIntAreGaugeErrors) {
    const Decoded itn = decode_itn("948912345678\r");
    ASSERT_EQ(itn.result, Decode::Valid);
    EXPECT_EQ(itn.reading.status, ReadingStatus::Error);
    EXPECT_EQ(itn.reading.code, 999'999'999);
    const Decoded sylvac = decode_sylvac("E123456789012\r");
    ASSERT_EQ(sylvac.result, Decode::Valid);
    EXPECT_EQ(sylvac.reading.status, ReadingStatus::Error);
    EXPECT_EQ(sylvac.reading.code, 999'999'999);
}

TEST(GaugeCodecs, SpcFrameFromTheManufacturersExample) {
    // d1..d13 = F F F F 0 2 1 0 7 6 5 4 0: +210765 × 10⁻⁴ mm = +21.0765 mm.
    const std::uint8_t frame[13] = {0xF, 0xF, 0xF, 0xF, 0, 2, 1, 0, 7, 6, 5, 4, 0};
    const Decoded d = decode_spc_frame(frame);
    ASSERT_EQ(d.result, Decode::Valid);
    EXPECT_NEAR(d.reading.value, 21.0765, 1e-12);
    EXPECT_FALSE(d.reading.inch);
    const std::uint8_t neg[13] = {0xF, 0xF, 0xF, 0xF, 8, 0, 1, 2, 3, 4, 5, 3, 0};  // -12.345 mm
    EXPECT_NEAR(decode_spc_frame(neg).reading.value, -12.345, 1e-12);
    std::uint8_t bad[13] = {0xF, 0xF, 0xF, 0xE, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    EXPECT_EQ(decode_spc_frame(bad).result, Decode::Invalid);
    EXPECT_EQ(decode_spc_frame(std::span<const std::uint8_t>(frame, 12)).result, Decode::NeedMore);
    // The emulator's encoder agrees with the decoder, inch flag included.
    const auto e = encode_spc_frame(-0.04861, 5, true);
    const Decoded back = decode_spc_frame(e);
    EXPECT_NEAR(back.reading.value, -0.04861, 1e-12);
    EXPECT_TRUE(back.reading.inch);
}

TEST(GaugeCodecs, ModbusRegistersAreSigned32BitTenthsOfMicrometres) {
    EXPECT_DOUBLE_EQ(modbus_reading(0x0000, 0x3039).value, 1.2345);
    EXPECT_DOUBLE_EQ(modbus_reading(0xFFFF, 0x34E0).value, -5.2);
    // The well-known check value of CRC-16/MODBUS for 01 03 00 00 00 02 is 0x0BC4 (sent C4 0B).
    const std::uint8_t req[] = {1, 3, 0, 0, 0, 2};
    EXPECT_EQ(modbus_crc(req), 0x0BC4);
}

TEST(GaugeUris, SchemesAndParameters) {
    EXPECT_TRUE(is_gauge_uri("sylvac:/dev/ttyUSB0"));
    EXPECT_TRUE(is_gauge_uri("mitutoyo-itn:"));
    EXPECT_FALSE(is_gauge_uri("serial:/dev/ttyACM0"));
    EXPECT_THROW(open_gauge("sylvac:"), std::invalid_argument);
    EXPECT_THROW(open_gauge("modbus:/dev/null?slave=0"), std::invalid_argument);
    EXPECT_THROW(open_gauge("modbus:/dev/null?speed=9600"), std::invalid_argument);
    EXPECT_THROW(open_gauge("sylvac:/dev/null?slave=2"), std::invalid_argument);
    try {
        open_gauge("digimatic:/nonexistent/tty");
        FAIL();
    } catch (const DeviceError& e) {
        EXPECT_NE(std::string(e.what()).find("/nonexistent/tty"), std::string::npos) << e.what();
    }
}

/// An emulated gauge behind a pty (serial kinds) or the in-process ITN link, opened by its driver.
struct Rig {
    explicit Rig(GaugeEmulatorConfig cfg, GaugeEmulator::Displacement disp = {}) : emu(cfg, std::move(disp), true) {
        if (cfg.kind == Kind::MitutoyoItn) {
            gauge = make_itn_gauge(make_emulated_itn_link(emu));
            return;
        }
        host = std::make_unique<GaugePtyHost>(emu);
        gauge = open_gauge(std::string(to_string(cfg.kind)) + ":" + host->path() +
                           (cfg.kind == Kind::Modbus ? "?slave=1&baud=38400" : ""));
    }
    GaugeEmulator emu;
    std::unique_ptr<GaugePtyHost> host;
    std::unique_ptr<Gauge> gauge;
};

class GaugeEmulators : public ::testing::TestWithParam<Kind> {};

TEST_P(GaugeEmulators, ReadsFollowTheBar) {
    GaugeEmulatorConfig cfg;
    cfg.kind = GetParam();
    cfg.noise_um = 0;
    cfg.offset_mm = 2.5;
    Rig rig(cfg, [](double t) { return 0.001 * t; });  // 1 µm/s
    const Identity id = rig.gauge->identify();
    EXPECT_EQ(id.kind, GetParam());
    EXPECT_FALSE(id.inch);
    for (int i = 0; i < 20; ++i) {
        const Reading r = rig.gauge->read(500ms);
        ASSERT_EQ(r.status, ReadingStatus::Ok);
        const double t = static_cast<double>(rig.emu.now_us()) * 1e-6;
        EXPECT_NEAR(r.value_mm(), 2.5 + 0.001 * t, 0.6e-4);
        EXPECT_NEAR(r.resolution_mm(), 1e-4, 1e-12);
    }
    if (GetParam() == Kind::MitutoyoItn) {
        EXPECT_EQ(id.serial, "EMU-G0001");
    }
}

TEST_P(GaugeEmulators, EveryFault) {
    GaugeEmulatorConfig cfg;
    cfg.kind = GetParam();
    Rig rig(cfg);
    rig.gauge->identify();
    auto with = [&](GaugeFaults f) {
        rig.emu.set_faults(f);
        try {
            return std::string(to_string(rig.gauge->read(150ms).status));
        } catch (const DeviceError& e) {
            return std::string(to_string(e.kind()));
        }
    };
    GaugeFaults f;
    f.not_ready_probability = 1;
    EXPECT_EQ(with(f), "not ready");
    f = {};
    f.out_of_range_probability = 1;
    EXPECT_EQ(with(f), "out of range");
    f = {};
    f.no_reply_probability = 1;
    EXPECT_EQ(with(f), "timeout");
    f = {};
    f.cut_off_probability = 1;
    EXPECT_EQ(with(f), "timeout");
    f = {};
    EXPECT_EQ(with(f), "ok");  // and it recovers
    f.inch = true;
    rig.emu.set_faults(f);
    const double tol = 1e-5 * 25.4;  // one inch digit
    switch (GetParam()) {
        case Kind::Sylvac: {  // UNI? tells the unit: the driver converts
            EXPECT_TRUE(rig.gauge->identify().inch);
            const Reading r = rig.gauge->read(500ms);
            EXPECT_TRUE(r.inch);
            EXPECT_NEAR(r.value_mm(), cfg.offset_mm, tol);
            break;
        }
        case Kind::Digimatic: {  // the SPC frame's unit digit travels in the adaptor's line
            const Reading r = rig.gauge->read(500ms);
            EXPECT_TRUE(r.inch);
            EXPECT_NEAR(r.value_mm(), cfg.offset_mm, tol);
            break;
        }
        case Kind::MitutoyoItn:  // the ITN line has no unit: it reads the inch figure (docs: set the gauge to mm)
            EXPECT_NEAR(rig.gauge->read(500ms).value, cfg.offset_mm / 25.4, 1e-5);
            break;
        case Kind::Modbus:  // the register is always mm × 10⁴
            EXPECT_NEAR(rig.gauge->read(500ms).value_mm(), cfg.offset_mm, 1e-3);
            break;
    }
    if (GetParam() == Kind::Sylvac) {
        f.low_battery = true;
        rig.emu.set_faults(f);
        EXPECT_TRUE(rig.gauge->identify().low_battery);
    }
}

TEST_P(GaugeEmulators, SamplerZeroesSignsAndMeasuresTheRate) {
    GaugeEmulatorConfig cfg;
    cfg.kind = GetParam();
    cfg.rate_hz = 25;
    cfg.noise_um = 0;
    cfg.sign = -1;
    double disp = 0;
    GaugeEmulator::Displacement f = [&disp](double) { return disp; };
    Rig rig(cfg, f);
    BarOnGauge bar;
    bar.calibrated_length_mm = 150;
    bar.sign = -1;
    bar.target_rate_hz = 25;
    GaugeSampler sampler(std::move(rig.gauge), bar, [&rig] { return rig.emu.now_us(); });
    sampler.identify();
    auto s = sampler.poll(500ms);
    ASSERT_TRUE(s);
    EXPECT_TRUE(s->flags & analysis::kSampleNotReferenced);
    sampler.set_zero(5);
    disp = 0.0123;  // the bar grows by 12.3 µm; the gauge, mounted reversed, reads less
    s = sampler.poll(500ms);
    ASSERT_TRUE(s);
    EXPECT_EQ(s->flags, analysis::kSampleTempInvalid);  // referenced; a gauge has no bar temperature
    EXPECT_NEAR(s->length_mm(150), 150.0123, 1e-7);
    EXPECT_NEAR(sampler.stats().rate_hz, 25, 0.01);
    EXPECT_NEAR(sampler.stats().resolution_mm, 1e-4, 1e-12);
    GaugeFaults nr;
    nr.not_ready_probability = 1;
    rig.emu.set_faults(nr);
    EXPECT_FALSE(sampler.poll(200ms));
    rig.emu.set_faults({});
    s = sampler.poll(500ms);
    ASSERT_TRUE(s);
    EXPECT_TRUE(s->flags & analysis::kSampleAfterGap);  // a reading was missed: never papered over
    EXPECT_EQ(sampler.stats().not_ready, 1u);
}

INSTANTIATE_TEST_SUITE_P(AllKinds, GaugeEmulators,
                         ::testing::Values(Kind::Sylvac, Kind::MitutoyoItn, Kind::Digimatic, Kind::Modbus),
                         [](const ::testing::TestParamInfo<Kind>& p) {
                             std::string n = to_string(p.param);
                             n.erase(std::remove(n.begin(), n.end(), '-'), n.end());
                             return n;
                         });

TEST(GaugeEmulators, RealTimeGaugeAnswersAtItsRate) {
    GaugeEmulatorConfig cfg;
    cfg.kind = Kind::Sylvac;
    cfg.rate_hz = 40;
    GaugeEmulator emu(cfg, {}, false);
    GaugePtyHost host(emu);
    BarOnGauge bar;
    bar.target_rate_hz = 1000;  // asks as fast as it can: the gauge is the limit
    GaugeSampler sampler(open_gauge("sylvac:" + host.path()), bar);
    sampler.identify();
    for (int i = 0; i < 20; ++i) ASSERT_TRUE(sampler.poll(500ms));
    EXPECT_NEAR(sampler.stats().rate_hz, 40, 6);
}

TEST(SlowGauge, MaxFeedForRate) {
    // 20 readings/s on a 150 mm circle, one reading a degree: 20 × 60 × 2π × 150 / 360 = 3141.6 mm/min.
    EXPECT_NEAR(max_feed_for_rate(20, 150, 1), 3141.59, 0.01);
    EXPECT_NEAR(max_feed_for_rate(10, 150, 2), 3141.59 / 4, 0.01);
    EXPECT_EQ(max_feed_for_rate(0, 150), 0);
}

}  // namespace
}  // namespace ballbar::device::gauge

TEST(GaugeHint, TheResumeLineTakesTheDeviceTheHintNames) {
    using ballbar::device::gauge::hinted_device;
    EXPECT_EQ(hinted_device("cannot open the instrument: serial:/dev/ttyUSB0: no answer to Identify within 500 ms; a "
                            "sylvac gauge answers on /dev/ttyUSB0: use --device sylvac:/dev/ttyUSB0"),
              "sylvac:/dev/ttyUSB0");
    EXPECT_EQ(hinted_device("(…: use --device modbus:/dev/ttyS0); everything measured is stored"), "modbus:/dev/ttyS0");
    EXPECT_FALSE(hinted_device("cannot open the instrument: no answer to Identify").has_value());
}
