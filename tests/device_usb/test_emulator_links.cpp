// SPDX-License-Identifier: MIT
// The whole chain: emulator (device model) -> fake USB bulk / HID device behind umockdev -> real libusb /
// hidapi -> our transports -> the real instrument driver. Identify, stream in real time with no loss,
// pull the cable mid-stream, plug it back and carry on.
#include <gtest/gtest.h>

#include <thread>

#include "ballbar/device/hid.hpp"
#include "ballbar/device/ids.hpp"
#include "ballbar/device/instrument.hpp"
#include "ballbar/device/usb.hpp"
#include "emulator_endpoint.hpp"
#include "fake_hid_device.hpp"
#include "fake_usb_device.hpp"

namespace ballbar::device::testing {
namespace {

using namespace std::chrono_literals;

EmulatorConfig config() {
    EmulatorConfig c;
    c.seed = 7;
    c.instrument.serial = "EMU00042";
    c.instrument.sample_rate_hz = 1000;
    return c;
}

/// Streams for `span`, returns the samples that arrived.
std::size_t stream_for(Instrument& inst, std::chrono::milliseconds span) {
    std::vector<analysis::BarSample> buf(4096);
    std::size_t got = 0;
    const auto end = std::chrono::steady_clock::now() + span;
    while (std::chrono::steady_clock::now() < end) {
        inst.poll(20ms);
        got += inst.read_samples(buf);
    }
    return got;
}

enum class Link { Usb, Hid };

class EmulatorOverUsb : public ::testing::TestWithParam<Link> {
  protected:
    void SetUp() override {
        if (!Testbed::preload_active()) GTEST_SKIP() << "needs LD_PRELOAD=libumockdev-preload.so.0";
        tb_ = std::make_unique<Testbed>();
        if (GetParam() == Link::Usb) {
            usb_ = std::make_unique<FakeUsbBulkDevice>(*tb_, emu_, kBallbarVendorId, kBallbarBulkProductId, "EMU00042");
        } else {
            hid_ = std::make_unique<FakeHidDevice>(*tb_, emu_, kBallbarVendorId, kBallbarHidProductId, "EMU00042");
        }
        plug();
    }
    void TearDown() override {
        hid_.reset();
        usb_.reset();
        tb_.reset();
    }
    void plug() { usb_ ? usb_->plug() : hid_->plug(); }
    void unplug() { usb_ ? usb_->unplug() : hid_->unplug(); }
    std::unique_ptr<Transport> open() {
        return usb_ ? open_usb_transport(kBallbarVendorId, kBallbarBulkProductId, "EMU00042")
                    : open_hid_transport(kBallbarVendorId, kBallbarHidProductId, "EMU00042");
    }

    RealTimeEmulator emu_{config()};
    std::unique_ptr<Testbed> tb_;
    std::unique_ptr<FakeUsbBulkDevice> usb_;
    std::unique_ptr<FakeHidDevice> hid_;
};

TEST_P(EmulatorOverUsb, IdentifiesAndStreamsWithoutLoss) {
    Instrument inst(open());
    const auto& info = inst.identify();
    EXPECT_EQ(info.model, "BB-1E");
    EXPECT_EQ(info.serial, "EMU00042");
    EXPECT_EQ(info.protocol_version, 1);
    inst.configure(1000, 1);
    inst.start_streaming();
    const std::size_t samples = stream_for(inst, 600ms);
    inst.stop_streaming();
    // 1 kHz for 0.6 s, less the start-up latency
    EXPECT_GE(samples, 400U);
    EXPECT_LE(samples, 700U);
    EXPECT_EQ(inst.stats().lost_frames, 0U);
    EXPECT_EQ(inst.stats().invalid_frames, 0U);
    EXPECT_EQ(inst.stats().gaps, 0U);
    EXPECT_EQ(emu_.with([](Emulator& e) { return e.counters().invalid_host_frames; }), 0U);
}

TEST_P(EmulatorOverUsb, CablePulledMidStreamThenBack) {
    {
        Instrument inst(open());
        inst.identify();
        inst.start_streaming();
        EXPECT_GT(stream_for(inst, 200ms), 50U);
        std::thread puller([&] {
            std::this_thread::sleep_for(100ms);
            unplug();
        });
        try {
            stream_for(inst, 3s);
            ADD_FAILURE() << "streaming went on after the cable was pulled";
        } catch (const DeviceError& e) {
            EXPECT_EQ(e.kind(), DeviceErrorKind::Disconnected) << e.what();
        }
        puller.join();
        try {
            inst.status();
            ADD_FAILURE() << "a request succeeded on an unplugged device";
        } catch (const DeviceError& e) {
            EXPECT_EQ(e.kind(), DeviceErrorKind::Disconnected) << e.what();
        }
    }
    try {
        open();
        ADD_FAILURE() << "opened an unplugged device";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::NotFound) << e.what();
    }

    plug();
    Instrument again(open());
    again.stop_streaming();  // the instrument kept streaming while nobody listened
    EXPECT_EQ(again.identify().serial, "EMU00042");
    again.start_streaming();
    EXPECT_GT(stream_for(again, 400ms), 200U);
    again.stop_streaming();
    EXPECT_EQ(again.stats().invalid_frames, 0U);
}

TEST_P(EmulatorOverUsb, SilentInstrumentTimesOut) {
    InstrumentOptions opt;
    opt.reply_timeout = 100ms;
    opt.attempts = 2;
    Instrument inst(open(), opt);
    emu_.with([](Emulator& e) {
        e.faults().stall_at_s = 0;
        e.faults().stall_s = 3600;
        return 0;
    });
    const auto t0 = std::chrono::steady_clock::now();
    try {
        inst.identify();
        FAIL() << "a stalled instrument answered";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::Timeout) << e.what();
    }
    EXPECT_LT(std::chrono::steady_clock::now() - t0, 2s);
}

INSTANTIATE_TEST_SUITE_P(Links, EmulatorOverUsb, ::testing::Values(Link::Usb, Link::Hid),
                         [](const auto& p) { return p.param == Link::Usb ? "UsbBulk" : "Hid"; });

}  // namespace
}  // namespace ballbar::device::testing
