// SPDX-License-Identifier: MIT
// The real libusb transport against a fake vendor bulk device behind umockdev.
#include <gtest/gtest.h>

#include <thread>

#include "ballbar/device/ids.hpp"
#include "ballbar/device/usb.hpp"
#include "fake_usb_device.hpp"
#include "link_helpers.hpp"

namespace ballbar::device::testing {
namespace {

using namespace std::chrono_literals;

class UsbLink : public ::testing::Test {
  protected:
    void SetUp() override {
        if (!Testbed::preload_active()) GTEST_SKIP() << "needs LD_PRELOAD=libumockdev-preload.so.0";
        tb_ = std::make_unique<Testbed>();
        dev_ = std::make_unique<FakeUsbBulkDevice>(*tb_, echo_, kBallbarVendorId, kBallbarBulkProductId, "BB0001");
        dev_->plug();
    }
    void TearDown() override {
        dev_.reset();
        tb_.reset();
    }
    EchoEndpoint echo_;
    std::unique_ptr<Testbed> tb_;
    std::unique_ptr<FakeUsbBulkDevice> dev_;
};

TEST_F(UsbLink, OpensByIdsAndReportsSerialInUri) {
    auto t = open_usb_transport(kBallbarVendorId, kBallbarBulkProductId, "");
    EXPECT_EQ(t->uri(), "usb:1209:0001:BB0001");
    auto by_serial = open_usb_transport(kBallbarVendorId, kBallbarBulkProductId, "BB0001");
    EXPECT_EQ(by_serial->uri(), "usb:1209:0001:BB0001");
}

TEST_F(UsbLink, UnknownSerialOrProductIsNotFound) {
    try {
        open_usb_transport(kBallbarVendorId, kBallbarBulkProductId, "NOPE");
        FAIL() << "opened a device with the wrong serial";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::NotFound);
        EXPECT_NE(std::string(e.what()).find("NOPE"), std::string::npos);
    }
    try {
        open_usb_transport(kBallbarVendorId, 0x0fff, "");
        FAIL() << "opened a device that is not there";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::NotFound);
    }
}

TEST_F(UsbLink, CarriesBytesBothWays) {
    auto t = open_usb_transport(kBallbarVendorId, kBallbarBulkProductId, "");
    const auto data = pattern(1000);  // many 64-byte packets, every byte value
    t->write(data, 500ms);
    EXPECT_EQ(read_bytes(*t, data.size(), 2s), data);
    EXPECT_EQ(echo_.received(), data);
    EXPECT_GT(dev_->in_transfers(), 0);
}

TEST_F(UsbLink, SmallReadsDoNotLoseBytes) {
    auto t = open_usb_transport(kBallbarVendorId, kBallbarBulkProductId, "");
    const auto data = pattern(200, 3);
    t->write(data, 500ms);
    std::vector<std::uint8_t> got;
    const auto deadline = std::chrono::steady_clock::now() + 2s;
    while (got.size() < data.size() && std::chrono::steady_clock::now() < deadline) {
        std::uint8_t b[3];
        const std::size_t n = t->read(b, 50ms);
        got.insert(got.end(), b, b + n);
    }
    EXPECT_EQ(got, data);
}

TEST_F(UsbLink, ReadTimesOutWithNothingPending) {
    auto t = open_usb_transport(kBallbarVendorId, kBallbarBulkProductId, "");
    std::uint8_t buf[64];
    const auto t0 = std::chrono::steady_clock::now();
    EXPECT_EQ(t->read(buf, 100ms), 0U);
    const auto took = std::chrono::steady_clock::now() - t0;
    EXPECT_GE(took, 90ms);
    EXPECT_LT(took, 1500ms);
    // the link still works after a timeout (the cancelled transfer lost nothing)
    const auto data = pattern(10);
    t->write(data, 500ms);
    EXPECT_EQ(read_bytes(*t, data.size(), 2s), data);
}

TEST_F(UsbLink, UnplugIsDisconnectedAndReplugReopens) {
    auto t = open_usb_transport(kBallbarVendorId, kBallbarBulkProductId, "");
    t->write(pattern(5), 500ms);
    EXPECT_EQ(read_bytes(*t, 5, 2s).size(), 5U);

    // pulled while a read is waiting
    std::thread puller([&] {
        std::this_thread::sleep_for(100ms);
        dev_->unplug();
    });
    std::uint8_t buf[64];
    try {
        for (int i = 0; i < 100; ++i) t->read(buf, 50ms);
        ADD_FAILURE() << "reads went on after the cable was pulled";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::Disconnected) << e.what();
    }
    puller.join();
    // every later call says the same, and the device is gone from the bus
    try {
        t->write(pattern(3), 100ms);
        ADD_FAILURE() << "write after unplug succeeded";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::Disconnected);
    }
    t.reset();
    try {
        open_usb_transport(kBallbarVendorId, kBallbarBulkProductId, "");
        ADD_FAILURE() << "opened an unplugged device";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::NotFound);
    }

    dev_->plug();
    auto again = open_usb_transport(kBallbarVendorId, kBallbarBulkProductId, "BB0001");
    const auto data = pattern(100, 9);
    again->write(data, 500ms);
    EXPECT_EQ(read_bytes(*again, data.size(), 2s), data);
}

TEST_F(UsbLink, WriteAfterUnplugIsDisconnected) {
    auto t = open_usb_transport(kBallbarVendorId, kBallbarBulkProductId, "");
    dev_->unplug();
    try {
        t->write(pattern(64), 200ms);
        FAIL() << "write to an unplugged device succeeded";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::Disconnected) << e.what();
    }
}

}  // namespace
}  // namespace ballbar::device::testing
