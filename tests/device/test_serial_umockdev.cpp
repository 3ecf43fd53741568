// SPDX-License-Identifier: MIT
// The real libserialport against the emulator behind a umockdev CDC-ACM testbed (/dev/ttyACM0 with
// its USB parent in sysfs, a pty underneath; the modem-line ioctls are answered here), following
// the set-up docs/device.md describes ("libserialport behind umockdev"). Runs under LD_PRELOAD=libumockdev-preload.
// Covers: enumeration with VID/PID, open/configure through libserialport, identify and lossless
// streaming through the driver, an unplug mid-stream (DeviceError{Disconnected}) and a replug.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <libserialport.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <umockdev.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <mutex>
#include <thread>

#include "ballbar/device/emulator.hpp"
#include "ballbar/device/ids.hpp"
#include "ballbar/device/instrument.hpp"
#include "ballbar/device/serial.hpp"

using namespace ballbar;
using namespace ballbar::device;
using namespace std::chrono_literals;

namespace {

constexpr const char* kIfSys = "/sys/devices/pci0000:00/0000:00:14.0/usb1/1-3/1-3:1.0";
constexpr const char* kUsbSys = "/sys/devices/pci0000:00/0000:00:14.0/usb1/1-3";

std::string tty_name(int n) {
    return "ttyACM" + std::to_string(n);
}
std::string tty_sys(int n) {
    return std::string(kIfSys) + "/tty/" + tty_name(n);
}

std::string description(int n) {
    const std::string vid = hex4(kBallbarVendorId), pid = hex4(kBallbarSerialProductId);
    const std::string tty = tty_name(n), minor = std::to_string(n);
    return "P: " + tty_sys(n).substr(4) + "\n" + "N: " + tty + "\nE: DEVNAME=/dev/" + tty +
           "\nE: MAJOR=166\nE: MINOR=" + minor + "\nE: SUBSYSTEM=tty\nA: dev=166:" + minor +
           "\\n\nL: device=../../../1-3:1.0\n\n"
           "P: /devices/pci0000:00/0000:00:14.0/usb1/1-3/1-3:1.0\n"
           "E: DEVTYPE=usb_interface\nE: DRIVER=cdc_acm\nE: INTERFACE=2/2/1\nE: SUBSYSTEM=usb\n"
           "A: bInterfaceClass=02\\n\nA: bInterfaceNumber=00\\n\n\n"
           "P: /devices/pci0000:00/0000:00:14.0/usb1/1-3\n"
           "E: DEVTYPE=usb_device\nE: SUBSYSTEM=usb\nE: PRODUCT=" +
           vid + "/" + pid +
           "/100\n"
           "A: busnum=1\\n\nA: devnum=4\\n\nA: idVendor=" +
           vid + "\\n\nA: idProduct=" + pid +
           "\\n\n"
           "A: manufacturer=Ballbar Project\\n\nA: product=BallBar BB-1E\\n\nA: serial=EMU00001\\n\n";
}

/// The emulator as a CDC-ACM device: the handler thread feeds it the host's writes; a pump thread
/// runs its clock (as fast as the host reads while streaming) and writes its bytes to the pty master.
class FakeAcm {
  public:
    explicit FakeAcm(EmulatorConfig cfg) : emu_(std::move(cfg)) {
        tb_ = umockdev_testbed_new();
        plug();
        pump_ = std::thread([this] { pump(); });
    }
    ~FakeAcm() {
        stop_ = true;
        pump_.join();
        if (handler_) g_object_unref(handler_);
        g_object_unref(tb_);
    }
    /// Plugs the device in; it appears as /dev/ttyACM<n> (the kernel gives a replugged device a new
    /// number while the old node is still held open, as here; umockdev cannot reuse a tty name either).
    void plug() {
        GError* err = nullptr;
        const std::string desc = description(generation_);
        ASSERT_TRUE(umockdev_testbed_add_from_string(tb_, desc.c_str(), &err)) << (err ? err->message : "");
        if (!handler_) {
            handler_ = umockdev_ioctl_base_new();
            g_signal_connect(handler_, "handle-ioctl", G_CALLBACK(on_ioctl), this);
            g_signal_connect(handler_, "handle-write", G_CALLBACK(on_write), this);
        }
        ASSERT_TRUE(umockdev_testbed_attach_ioctl(tb_, node().c_str(), handler_, &err)) << (err ? err->message : "");
        std::lock_guard lock(m_);
        master_ = umockdev_testbed_get_dev_fd(tb_, node().c_str());
        plugged_ = true;
    }
    void unplug() {
        namespace fs = std::filesystem;
        gchar* root = umockdev_testbed_get_root_dir(tb_);  // transfer full
        const fs::path dev = fs::path(root) / "dev";
        g_free(root);
        std::error_code ec;
        std::string ptymap_key = fs::read_symlink(dev / tty_name(generation_), ec).string();
        for (auto& c : ptymap_key) c = c == '/' ? '_' : c;
        {
            std::lock_guard lock(m_);
            plugged_ = false;
            // The kernel hangs up a CDC-ACM tty whose device goes away. umockdev keeps the pty master open
            // across remove_device, so hang up ourselves: put /dev/null on the master's descriptor number
            // (the testbed may still close that number later), which closes the pty and hangs up the slave.
            const int null_fd = ::open("/dev/null", O_RDWR | O_CLOEXEC);
            ::dup2(null_fd, master_);
            ::close(null_fd);
            master_ = -1;
            emu_.host_link_lost();  // bus-powered: the instrument lost power with the cable
        }
        umockdev_testbed_detach_ioctl(tb_, node().c_str(), nullptr);
        umockdev_testbed_uevent(tb_, tty_sys(generation_).c_str(), "remove");
        umockdev_testbed_remove_device(tb_, tty_sys(generation_).c_str());
        umockdev_testbed_remove_device(tb_, kIfSys);
        umockdev_testbed_remove_device(tb_, kUsbSys);
        fs::remove(dev / ".ptymap" / ptymap_key, ec);  // the freed pty number may come back
        ++generation_;
    }
    std::string node() const { return "/dev/" + tty_name(generation_); }
    std::uint64_t sent_frames() {
        std::lock_guard lock(m_);
        return emu_.counters().stream_frames;
    }

  private:
    static gboolean on_ioctl(UMockdevIoctlBase*, UMockdevIoctlClient* c, gpointer self_ptr) {
        auto* self = static_cast<FakeAcm*>(self_ptr);
        const gulong req = umockdev_ioctl_client_get_request(c);
        if (req == TIOCMGET || req == TIOCMSET || req == TIOCMBIS || req == TIOCMBIC) {
            UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(c);
            UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, sizeof(int), nullptr);
            int* v = reinterpret_cast<int*>(d->data);
            if (req == TIOCMGET) {
                *v = self->modem_bits_;
            } else if (req == TIOCMSET) {
                self->modem_bits_ = *v;
            } else if (req == TIOCMBIS) {
                self->modem_bits_ |= *v;
            } else {
                self->modem_bits_ &= ~*v;
            }
            umockdev_ioctl_client_complete(c, 0, 0);
            g_object_unref(d);
            return TRUE;
        }
        int err = 0;
        const glong r = umockdev_ioctl_client_execute(c, &err, nullptr);  // termios etc. on the real pty
        umockdev_ioctl_client_complete(c, r, err);
        return TRUE;
    }
    static gboolean on_write(UMockdevIoctlBase*, UMockdevIoctlClient* c, gpointer self_ptr) {
        auto* self = static_cast<FakeAcm*>(self_ptr);
        UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(c);
        {
            std::lock_guard lock(self->m_);
            self->emu_.on_host_bytes({arg->data, static_cast<std::size_t>(arg->data_len)});
        }
        umockdev_ioctl_client_complete(c, static_cast<glong>(arg->data_len), 0);
        return TRUE;
    }
    void pump() {
        std::array<std::uint8_t, 4096> buf{};
        std::size_t have = 0, off = 0;
        auto last = std::chrono::steady_clock::now();
        while (!stop_) {
            int fd;
            {
                std::lock_guard lock(m_);
                fd = master_;
                const auto now = std::chrono::steady_clock::now();
                const auto real_us = std::chrono::duration_cast<std::chrono::microseconds>(now - last).count();
                last = now;
                std::uint64_t t = emu_.now_us() + static_cast<std::uint64_t>(real_us);
                if (emu_.streaming() && emu_.pending_output() < 8192) t = std::max(t, emu_.now_us() + 5000);
                emu_.advance_to(t);
                if (!plugged_) {
                    std::array<std::uint8_t, 4096> sink{};
                    while (emu_.take_device_bytes(sink) > 0) {
                    }  // nobody to hear it
                    have = off = 0;
                } else if (off == have) {
                    have = emu_.take_device_bytes(buf);
                    off = 0;
                }
            }
            if (fd < 0 || off == have) {
                std::this_thread::sleep_for(200us);
                continue;
            }
            pollfd p{fd, POLLOUT, 0};
            if (::poll(&p, 1, 5) == 1 && (p.revents & POLLOUT)) {
                const ssize_t n = ::write(fd, buf.data() + off, have - off);
                if (n > 0) off += static_cast<std::size_t>(n);
            }
        }
    }

    UMockdevTestbed* tb_ = nullptr;
    UMockdevIoctlBase* handler_ = nullptr;
    std::mutex m_;
    Emulator emu_;
    int master_ = -1;
    bool plugged_ = false;
    int generation_ = 0;
    std::atomic<int> modem_bits_{TIOCM_CTS | TIOCM_DSR | TIOCM_CD};
    std::atomic<bool> stop_{false};
    std::thread pump_;
};

bool preload_active() {
    const char* p = std::getenv("LD_PRELOAD");
    return p && std::string(p).find("libumockdev-preload") != std::string::npos;
}

std::size_t stream_serial_umockdev(Instrument& inst, std::size_t wanted) {
    std::vector<analysis::BarSample> buf(4096);
    std::size_t have = 0;
    std::uint64_t first = 0;
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    while (have < wanted && std::chrono::steady_clock::now() < deadline) {
        inst.poll(50ms);
        std::size_t n;
        while ((n = inst.read_samples(buf)) > 0) {
            if (have == 0) first = buf[0].seq;
            for (std::size_t i = 0; i < n; ++i) {
                if (buf[i].seq != first + have + i) throw std::runtime_error("host sequence not contiguous");
            }
            have += n;
        }
    }
    return have;
}

class SerialUmockdev : public ::testing::Test {
  protected:
    void SetUp() override {
        if (!preload_active()) GTEST_SKIP() << "needs LD_PRELOAD=libumockdev-preload.so.0 (ctest sets it)";
        EmulatorConfig cfg;
        cfg.seed = 11;
        cfg.instrument.sample_rate_hz = 5000;
        acm_ = std::make_unique<FakeAcm>(cfg);
    }
    std::unique_ptr<FakeAcm> acm_;
};

}  // namespace

TEST_F(SerialUmockdev, LibserialportListsThePortWithItsUsbIds) {
    sp_port** list = nullptr;
    ASSERT_EQ(sp_list_ports(&list), SP_OK);
    bool found = false;
    for (int i = 0; list[i]; ++i) {
        if (std::string(sp_get_port_name(list[i])) != "/dev/ttyACM0") continue;
        found = true;
        int vid = 0, pid = 0;
        ASSERT_EQ(sp_get_port_usb_vid_pid(list[i], &vid, &pid), SP_OK);
        EXPECT_EQ(vid, kBallbarVendorId);
        EXPECT_EQ(pid, kBallbarSerialProductId);
        EXPECT_EQ(sp_get_port_transport(list[i]), SP_TRANSPORT_USB);
        EXPECT_STREQ(sp_get_port_usb_serial(list[i]), "EMU00001");
    }
    sp_free_port_list(list);
    EXPECT_TRUE(found);
}

TEST_F(SerialUmockdev, IdentifyAndStreamThroughLibserialport) {
    Instrument inst(open_libserialport_transport("/dev/ttyACM0"));
    EXPECT_EQ(inst.transport().uri(), "serial:/dev/ttyACM0");
    EXPECT_EQ(inst.identify().serial, "EMU00001");
    EXPECT_EQ(inst.status().sample_rate_hz, 5000);
    inst.start_streaming();
    EXPECT_GE(stream_serial_umockdev(inst, 20000), 20000u);
    inst.stop_streaming();
    EXPECT_EQ(inst.stats().lost_frames, 0u);
    EXPECT_EQ(inst.stats().invalid_frames, 0u);
}

/// The port of our instrument with this USB serial number, found the way `ballbar devices` does.
std::string find_port(const std::string& serial) {
    sp_port** list = nullptr;
    if (sp_list_ports(&list) != SP_OK) return {};
    std::string found;
    for (int i = 0; list[i]; ++i) {
        int vid = 0, pid = 0;
        if (sp_get_port_usb_vid_pid(list[i], &vid, &pid) != SP_OK) continue;
        const char* sn = sp_get_port_usb_serial(list[i]);
        if (vid == kBallbarVendorId && pid == kBallbarSerialProductId && sn && serial == sn) {
            found = sp_get_port_name(list[i]);
        }
    }
    sp_free_port_list(list);
    return found;
}

TEST_F(SerialUmockdev, UnplugMidStreamThenReplug) {
    ASSERT_EQ(find_port("EMU00001"), "/dev/ttyACM0");
    {
        Instrument inst(open_serial_transport("/dev/ttyACM0"));
        inst.identify();
        inst.start_streaming();
        ASSERT_GE(stream_serial_umockdev(inst, 2000), 2000u);
        acm_->unplug();
        try {
            stream_serial_umockdev(inst, 100'000'000);
            FAIL() << "the unplug was not reported";
        } catch (const DeviceError& e) {
            EXPECT_EQ(e.kind(), DeviceErrorKind::Disconnected) << e.what();
        }
        EXPECT_FALSE(inst.streaming());
        try {
            open_serial_transport("/dev/ttyACM0");
            FAIL() << "opened an unplugged port";
        } catch (const DeviceError& e) {
            EXPECT_EQ(e.kind(), DeviceErrorKind::NotFound) << e.what();
        }
        EXPECT_EQ(find_port("EMU00001"), "");
        acm_->plug();  // while the old port is still open: it comes back as ttyACM1
    }
    const std::string port = find_port("EMU00001");
    ASSERT_EQ(port, "/dev/ttyACM1");
    Instrument again(open_serial_transport(port));
    EXPECT_EQ(again.identify().serial, "EMU00001");
    EXPECT_FALSE(again.status().streaming);  // the unplug stopped the stream
    again.start_streaming();
    EXPECT_GE(stream_serial_umockdev(again, 5000), 5000u);
    EXPECT_EQ(again.stats().lost_frames, 0u);
}
