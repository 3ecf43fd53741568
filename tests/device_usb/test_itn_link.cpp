// SPDX-License-Identifier: MIT
// The Mitutoyo USB-ITN driver through the real libusb against a fake ITN cable behind umockdev, answered
// by the gauge emulator: init by vendor control transfers, commands by vendor control, replies on the
// interrupt-IN endpoint; its faults; and `ballbar devices`' enumeration of it with its USB IDs.
#include <gtest/gtest.h>

#include "ballbar/device/enumerate.hpp"
#include "ballbar/device/gauge.hpp"
#include "ballbar/device/gauge_emulator.hpp"
#include "fake_itn_device.hpp"

namespace ballbar::device::testing {
namespace {

using namespace std::chrono_literals;
namespace gg = ballbar::device::gauge;

class ItnLink : public ::testing::Test {
  protected:
    void SetUp() override {
        if (!Testbed::preload_active()) GTEST_SKIP() << "needs LD_PRELOAD=libumockdev-preload.so.0";
        gg::GaugeEmulatorConfig cfg;
        cfg.kind = gg::Kind::MitutoyoItn;
        cfg.noise_um = 0;
        cfg.resolution_mm = 0.001;
        emu_ = std::make_unique<gg::GaugeEmulator>(
            cfg, [](double t) { return 0.01 * t; }, true);
        tb_ = std::make_unique<Testbed>();
        dev_ = std::make_unique<FakeItnDevice>(*tb_, *emu_, "ITN0042");
        dev_->plug();
    }
    void TearDown() override {
        dev_.reset();
        tb_.reset();
    }
    std::unique_ptr<gg::GaugeEmulator> emu_;
    std::unique_ptr<Testbed> tb_;
    std::unique_ptr<FakeItnDevice> dev_;
};

TEST_F(ItnLink, InitIdentifyAndReadThroughLibusb) {
    auto g = gg::open_gauge("mitutoyo-itn:");
    EXPECT_EQ(g->uri(), "mitutoyo-itn:ITN0042");
    const gg::Identity id = g->identify();
    EXPECT_EQ(id.maker, "Mitutoyo");
    EXPECT_EQ(id.model, "USB-ITN");
    EXPECT_EQ(id.serial, "ITN0042");
    EXPECT_EQ(id.firmware, "USB-ITN EMU 1.00");
    for (int i = 0; i < 10; ++i) {
        const gg::Reading r = g->read(500ms);
        ASSERT_EQ(r.status, gg::ReadingStatus::Ok);
        const double t = static_cast<double>(emu_->now_us()) * 1e-6;
        EXPECT_NEAR(r.value_mm(), 3.2105 + 0.01 * t, 0.6e-3);
        EXPECT_EQ(r.decimals, 3);
    }
    EXPECT_GE(dev_->vendor_requests(), 13);  // init, status, V, ten readings
    EXPECT_GT(dev_->in_transfers(), 10);     // 13-byte lines come in 8-byte reports
}

TEST_F(ItnLink, FaultsThroughLibusb) {
    auto g = gg::open_gauge("mitutoyo-itn:ITN0042");
    gg::GaugeFaults f;
    f.not_ready_probability = 1;
    emu_->set_faults(f);
    EXPECT_EQ(g->read(200ms).status, gg::ReadingStatus::NotReady);
    f = {};
    f.out_of_range_probability = 1;
    emu_->set_faults(f);
    EXPECT_EQ(g->read(200ms).status, gg::ReadingStatus::OutOfRange);
    for (auto which : {0, 1}) {
        f = {};
        (which == 0 ? f.no_reply_probability : f.cut_off_probability) = 1;
        emu_->set_faults(f);
        try {
            g->read(100ms);
            ADD_FAILURE() << "read without a whole reply";
        } catch (const DeviceError& e) {
            EXPECT_EQ(e.kind(), DeviceErrorKind::Timeout) << e.what();
        }
    }
    emu_->set_faults({});
    EXPECT_EQ(g->read(500ms).status, gg::ReadingStatus::Ok);
}

TEST_F(ItnLink, WrongSerialIsNotFound) {
    try {
        gg::open_gauge("mitutoyo-itn:NOPE");
        FAIL();
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::NotFound);
        EXPECT_NE(std::string(e.what()).find("0fe7:4001"), std::string::npos) << e.what();
    }
}

TEST_F(ItnLink, EnumeratedWithItsUsbIds) {
    const Enumeration e = enumerate_instruments();
    bool found = false;
    for (const auto& f : e.instruments) {
        if (f.uri != "mitutoyo-itn:ITN0042") continue;
        found = true;
        EXPECT_EQ(f.vid, 0x0fe7);
        EXPECT_EQ(f.pid, 0x4001);
        EXPECT_EQ(f.model, "USB-ITN");
        EXPECT_EQ(f.serial, "ITN0042");
    }
    EXPECT_TRUE(found);
}

}  // namespace
}  // namespace ballbar::device::testing
