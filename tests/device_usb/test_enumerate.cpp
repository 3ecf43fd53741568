// SPDX-License-Identifier: MIT
// Discovery of instruments on all three links, in-process and through `ballbar devices`, against fake
// devices behind umockdev (the CLI child process inherits the testbed through $UMOCKDEV_DIR).
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "ballbar/device/enumerate.hpp"
#include "ballbar/device/uri.hpp"
#include "fake_hid_device.hpp"
#include "fake_usb_device.hpp"

namespace ballbar::device::testing {
namespace {

// A CDC-ACM port as the kernel shows it (libserialport reads VID/PID/serial from the usb parent).
const char* const kAcm = R"(P: /devices/pci0000:00/0000:00:14.0/usb1/1-3/1-3:1.0/tty/ttyACM0
N: ttyACM0
E: DEVNAME=/dev/ttyACM0
E: MAJOR=166
E: MINOR=0
E: SUBSYSTEM=tty
A: dev=166:0\n
L: device=../../../1-3:1.0

P: /devices/pci0000:00/0000:00:14.0/usb1/1-3/1-3:1.0
E: DEVTYPE=usb_interface
E: DRIVER=cdc_acm
E: INTERFACE=2/2/1
E: SUBSYSTEM=usb
A: bInterfaceClass=02\n
A: bInterfaceNumber=00\n

P: /devices/pci0000:00/0000:00:14.0/usb1/1-3
E: DEVTYPE=usb_device
E: SUBSYSTEM=usb
E: PRODUCT=1209/3/100
A: busnum=1\n
A: devnum=4\n
A: idVendor=1209\n
A: idProduct=0003\n
A: manufacturer=Acme Metrology\n
A: product=BallBar BB-1S\n
A: serial=BB0003\n
)";

// Some other vendor's serial adapter: must not be listed.
const char* const kOtherAcm = R"(P: /devices/pci0000:00/0000:00:14.0/usb1/1-4/1-4:1.0/tty/ttyACM1
N: ttyACM1
E: DEVNAME=/dev/ttyACM1
E: MAJOR=166
E: MINOR=1
E: SUBSYSTEM=tty
A: dev=166:1\n
L: device=../../../1-4:1.0

P: /devices/pci0000:00/0000:00:14.0/usb1/1-4/1-4:1.0
E: DEVTYPE=usb_interface
E: DRIVER=cdc_acm
E: SUBSYSTEM=usb
A: bInterfaceClass=02\n
A: bInterfaceNumber=00\n

P: /devices/pci0000:00/0000:00:14.0/usb1/1-4
E: DEVTYPE=usb_device
E: SUBSYSTEM=usb
A: busnum=1\n
A: devnum=5\n
A: idVendor=2341\n
A: idProduct=0043\n
A: product=Arduino Uno\n
A: serial=X1\n
)";

class Enumerate : public ::testing::Test {
  protected:
    void SetUp() override {
        if (!Testbed::preload_active()) GTEST_SKIP() << "needs LD_PRELOAD=libumockdev-preload.so.0";
        tb_ = std::make_unique<Testbed>();
    }
    void plug_all() {
        usb_ = std::make_unique<FakeUsbBulkDevice>(*tb_, echo_, kBallbarVendorId, kBallbarBulkProductId, "BB0001");
        usb_->plug();
        hid_ = std::make_unique<FakeHidDevice>(*tb_, echo_, kBallbarVendorId, kBallbarHidProductId, "BB0002");
        hid_->plug();
        tb_->add(kAcm);
        tb_->add(kOtherAcm);
    }
    void TearDown() override {
        hid_.reset();
        usb_.reset();
        tb_.reset();
    }
    EchoEndpoint echo_;
    std::unique_ptr<Testbed> tb_;
    std::unique_ptr<FakeUsbBulkDevice> usb_;
    std::unique_ptr<FakeHidDevice> hid_;
};

TEST_F(Enumerate, NothingAttachedIsAnEmptyList) {
    const auto e = enumerate_instruments();
    EXPECT_TRUE(e.instruments.empty());
    EXPECT_TRUE(e.warnings.empty()) << e.warnings.front();  // an empty machine is not a problem
}

TEST_F(Enumerate, FindsOneInstrumentPerLink) {
    plug_all();
    const auto e = enumerate_instruments();
    ASSERT_EQ(e.instruments.size(), 3U);
    const auto& s = e.instruments[0];
    EXPECT_EQ(s.link, UsbLink::Serial);
    EXPECT_EQ(s.path, "/dev/ttyACM0");
    EXPECT_EQ(s.uri, "serial:/dev/ttyACM0");
    EXPECT_EQ(s.serial, "BB0003");
    EXPECT_EQ(s.model, "BallBar BB-1S");
    const auto& u = e.instruments[1];
    EXPECT_EQ(u.link, UsbLink::UsbBulk);
    EXPECT_EQ(u.path, usb_->node());
    EXPECT_EQ(u.uri, "usb:1209:0001:BB0001");
    EXPECT_EQ(u.model, "BallBar BB-1");
    EXPECT_TRUE(u.note.empty()) << u.note;
    const auto& h = e.instruments[2];
    EXPECT_EQ(h.link, UsbLink::Hid);
    EXPECT_EQ(h.path, "/dev/hidraw0");
    EXPECT_EQ(h.uri, "hid:1209:0002:BB0002");
    EXPECT_EQ(h.serial, "BB0002");
}

TEST_F(Enumerate, ListedUrisOpenThroughTheUriFactory) {
    plug_all();
    const auto e = enumerate_instruments();
    int opened = 0;
    for (const auto& f : e.instruments) {
        if (f.link == UsbLink::Serial) continue;  // a bare sysfs tty here, nothing to talk to
        auto t = open_transport(f.uri);
        EXPECT_EQ(t->uri(), f.uri);
        ++opened;
    }
    EXPECT_EQ(opened, 2);
}

std::pair<int, std::string> run(const std::string& cmd) {
    std::string out;
    FILE* p = popen(cmd.c_str(), "r");
    if (!p) return {-1, out};
    std::array<char, 4096> buf{};
    std::size_t n = 0;
    while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) out.append(buf.data(), n);
    const int status = pclose(p);
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

TEST_F(Enumerate, CliListsThemAsJson) {
    plug_all();
    const auto [code, out] = run(std::string(BALLBAR_EXE) + " devices --json");
    ASSERT_EQ(code, 0) << out;
    const auto j = nlohmann::json::parse(out);
    ASSERT_TRUE(j.is_array());
    ASSERT_EQ(j.size(), 3U) << out;
    EXPECT_EQ(j[0]["link"], "serial");
    EXPECT_EQ(j[0]["path"], "/dev/ttyACM0");
    EXPECT_EQ(j[1]["link"], "usb");
    EXPECT_EQ(j[1]["uri"], "usb:1209:0001:BB0001");
    EXPECT_EQ(j[1]["serial"], "BB0001");
    EXPECT_EQ(j[2]["link"], "hid");
    EXPECT_EQ(j[2]["model"], "BallBar BB-1H");
    EXPECT_EQ(j[2]["vid"], "1209");
    EXPECT_EQ(j[2]["pid"], "0002");
}

TEST_F(Enumerate, CliWithNothingAttachedSucceeds) {
    const auto [code, out] = run(std::string(BALLBAR_EXE) + " devices --json");
    EXPECT_EQ(code, 0);
    EXPECT_EQ(nlohmann::json::parse(out), nlohmann::json::array());
    const auto [code2, text] = run(std::string(BALLBAR_EXE) + " devices");
    EXPECT_EQ(code2, 0);
    EXPECT_NE(text.find("no instruments found"), std::string::npos) << text;
}

}  // namespace
}  // namespace ballbar::device::testing
