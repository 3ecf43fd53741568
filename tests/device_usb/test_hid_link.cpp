// SPDX-License-Identifier: MIT
// The real hidapi (hidraw) transport against a fake hidraw device behind umockdev.
#include <gtest/gtest.h>

#include <thread>

#include "ballbar/device/hid.hpp"
#include "ballbar/device/ids.hpp"
#include "fake_hid_device.hpp"
#include "link_helpers.hpp"

namespace ballbar::device::testing {
namespace {

using namespace std::chrono_literals;

TEST(HidReports, PackAndUnpackRoundTrip) {
    const auto data = pattern(200);
    const auto reports = hid_pack_reports(data);
    ASSERT_EQ(reports.size(), 4U);  // 63 + 63 + 63 + 11
    EXPECT_EQ(reports[0][0], 63);
    EXPECT_EQ(reports[3][0], 11);
    EXPECT_EQ(reports[3][12], 0);  // padding is zero
    std::vector<std::uint8_t> back;
    for (const auto& r : reports) {
        const auto p = hid_report_payload(r);
        back.insert(back.end(), p.begin(), p.end());
    }
    EXPECT_EQ(back, data);
    EXPECT_TRUE(hid_pack_reports({}).empty());
}

TEST(HidReports, OversizedLengthByteIsAProtocolError) {
    std::array<std::uint8_t, kHidReportSize> r{};
    r[0] = 64;
    try {
        hid_report_payload(r);
        FAIL();
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::Protocol);
    }
}

class HidLink : public ::testing::Test {
  protected:
    void SetUp() override {
        if (!Testbed::preload_active()) GTEST_SKIP() << "needs LD_PRELOAD=libumockdev-preload.so.0";
        tb_ = std::make_unique<Testbed>();
        dev_ = std::make_unique<FakeHidDevice>(*tb_, echo_, kBallbarVendorId, kBallbarHidProductId, "BB0002");
        dev_->plug();
    }
    void TearDown() override {
        dev_.reset();
        tb_.reset();
    }
    EchoEndpoint echo_;
    std::unique_ptr<Testbed> tb_;
    std::unique_ptr<FakeHidDevice> dev_;
};

TEST_F(HidLink, OpensByIdsAndReportsSerialInUri) {
    auto t = open_hid_transport(kBallbarVendorId, kBallbarHidProductId, "");
    EXPECT_EQ(t->uri(), "hid:1209:0002:BB0002");
    auto by_serial = open_hid_transport(kBallbarVendorId, kBallbarHidProductId, "BB0002");
    EXPECT_EQ(by_serial->uri(), "hid:1209:0002:BB0002");
}

TEST_F(HidLink, UnknownSerialIsNotFound) {
    try {
        open_hid_transport(kBallbarVendorId, kBallbarHidProductId, "NOPE");
        FAIL() << "opened a device with the wrong serial";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::NotFound);
    }
}

TEST_F(HidLink, CarriesBytesBothWaysInReports) {
    auto t = open_hid_transport(kBallbarVendorId, kBallbarHidProductId, "");
    const auto data = pattern(1000);  // 16 reports, every byte value
    t->write(data, 500ms);
    EXPECT_EQ(read_bytes(*t, data.size(), 3s), data);
    EXPECT_EQ(echo_.received(), data);
    EXPECT_EQ(dev_->reports_received(), 16);
}

TEST_F(HidLink, ReadTimesOutWithNothingPending) {
    auto t = open_hid_transport(kBallbarVendorId, kBallbarHidProductId, "");
    std::uint8_t buf[64];
    const auto t0 = std::chrono::steady_clock::now();
    EXPECT_EQ(t->read(buf, 100ms), 0U);
    const auto took = std::chrono::steady_clock::now() - t0;
    EXPECT_GE(took, 90ms);
    EXPECT_LT(took, 1500ms);
    const auto data = pattern(10);
    t->write(data, 500ms);
    EXPECT_EQ(read_bytes(*t, data.size(), 2s), data);
}

TEST_F(HidLink, UnplugIsDisconnectedAndReplugReopens) {
    auto t = open_hid_transport(kBallbarVendorId, kBallbarHidProductId, "");
    t->write(pattern(5), 500ms);
    EXPECT_EQ(read_bytes(*t, 5, 2s).size(), 5U);

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
    try {
        t->write(pattern(3), 100ms);
        ADD_FAILURE() << "write after unplug succeeded";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::Disconnected);
    }
    t.reset();
    try {
        open_hid_transport(kBallbarVendorId, kBallbarHidProductId, "");
        ADD_FAILURE() << "opened an unplugged device";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::NotFound);
    }

    dev_->plug();
    auto again = open_hid_transport(kBallbarVendorId, kBallbarHidProductId, "BB0002");
    const auto data = pattern(100, 9);
    again->write(data, 500ms);
    EXPECT_EQ(read_bytes(*again, data.size(), 2s), data);
}

TEST_F(HidLink, WriteAfterUnplugIsDisconnected) {
    auto t = open_hid_transport(kBallbarVendorId, kBallbarHidProductId, "");
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
