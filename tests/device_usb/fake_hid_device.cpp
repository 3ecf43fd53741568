// SPDX-License-Identifier: MIT
#include "fake_hid_device.hpp"

#include <fcntl.h>
#include <linux/hidraw.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "ballbar/device/hid.hpp"

namespace ballbar::device::testing {

struct FakeHidDevice::Handle {
    FakeHidDevice* dev;
    int generation;
    std::string node;
    UMockdevIoctlBase* base;
};

namespace {

// Vendor page 0xff00: one 64-byte input report and one 64-byte output report, no report IDs.
const std::uint8_t kReportDescriptor[] = {0x06, 0x00, 0xFF, 0x09, 0x01, 0xA1, 0x01, 0x09, 0x02, 0x15, 0x00, 0x26,
                                          0xFF, 0x00, 0x75, 0x08, 0x95, 0x40, 0x81, 0x02, 0x09, 0x03, 0x15, 0x00,
                                          0x26, 0xFF, 0x00, 0x75, 0x08, 0x95, 0x40, 0x91, 0x02, 0xC0};

std::string hid_dir(int index, std::uint16_t vid, std::uint16_t pid) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "/devices/pci0000:00/0000:00:14.0/usb1/1-2/1-2:1.0/0003:%04X:%04X.%04X", vid, pid,
                  index + 1);
    return buf;
}

}  // namespace

FakeHidDevice::FakeHidDevice(Testbed& tb, DeviceEndpoint& endpoint, std::uint16_t vid, std::uint16_t pid,
                             std::string serial)
    : tb_(tb), endpoint_(endpoint), vid_(vid), pid_(pid), serial_(std::move(serial)) {}

FakeHidDevice::~FakeHidDevice() {
    stop_ = true;
    if (pump_.joinable()) pump_.join();
    for (Handle* h : handles_) {
        umockdev_testbed_detach_ioctl(tb_.get(), h->node.c_str(), nullptr);
        g_object_unref(h->base);
        delete h;
    }
}

std::string FakeHidDevice::node() const {
    std::lock_guard lock(m_);
    return "/dev/hidraw" + std::to_string(generation_ - 1);
}

int FakeHidDevice::reports_received() const {
    std::lock_guard lock(m_);
    return reports_received_;
}

std::string FakeHidDevice::description(int index) const {
    char hid_id[80];
    std::snprintf(hid_id, sizeof hid_id, "0003:%08X:%08X", vid_, pid_);
    char vp[24];
    std::snprintf(vp, sizeof vp, "%x/%x/100", vid_, pid_);
    char usbids[64];
    std::snprintf(usbids, sizeof usbids, "A: idVendor=%04x\\n\nA: idProduct=%04x\\n\n", vid_, pid_);
    const std::string hid = hid_dir(index, vid_, pid_);
    const std::string raw = "hidraw" + std::to_string(index);
    const int devnum = 10 + index;
    std::string d;
    d += "P: " + hid + "/hidraw/" + raw + "\nN: " + raw + "\nE: DEVNAME=/dev/" + raw + "\n";
    d += "E: MAJOR=240\nE: MINOR=" + std::to_string(index) + "\nE: SUBSYSTEM=hidraw\n";
    d += "A: dev=240:" + std::to_string(index) + "\\n\n";
    d += "L: device=../../../" + hid.substr(hid.rfind('/') + 1) + "\n\n";
    d += "P: " + hid + "\nE: DRIVER=hid-generic\nE: HID_ID=" + hid_id + "\n";
    d += "E: HID_NAME=Acme Metrology BallBar BB-1H\nE: HID_PHYS=usb-0000:00:14.0-2/input0\n";
    d += "E: HID_UNIQ=" + serial_ + "\nE: SUBSYSTEM=hid\n";
    d += "H: report_descriptor=" + to_hex(kReportDescriptor) + "\n\n";
    d += "P: /devices/pci0000:00/0000:00:14.0/usb1/1-2/1-2:1.0\nE: DEVTYPE=usb_interface\nE: DRIVER=usbhid\n";
    d += std::string("E: PRODUCT=") + vp + "\nE: INTERFACE=3/0/0\nE: SUBSYSTEM=usb\n";
    d += "A: bInterfaceClass=03\\n\nA: bInterfaceNumber=00\\n\nA: bNumEndpoints=02\\n\n\n";
    d += "P: /devices/pci0000:00/0000:00:14.0/usb1/1-2\nE: SUBSYSTEM=usb\nE: DEVTYPE=usb_device\n";
    d += std::string("E: PRODUCT=") + vp + "\nE: BUSNUM=001\nE: DEVNUM=0" + std::to_string(devnum) + "\n";
    d += usbids;
    d += "A: busnum=1\\n\nA: devnum=" + std::to_string(devnum) + "\\n\nA: speed=12\\n\nA: bcdDevice=0100\\n\n";
    d += "A: manufacturer=Acme Metrology\\n\nA: product=BallBar BB-1H\\n\nA: serial=" + serial_ + "\\n\n";
    return d;
}

void FakeHidDevice::plug() {
    Handle* h = nullptr;
    int index = 0;
    {
        std::lock_guard lock(m_);
        if (present_) return;
        index = generation_++;
        h = new Handle{this, generation_, "/dev/hidraw" + std::to_string(index), umockdev_ioctl_base_new()};
        handles_.push_back(h);
    }
    tb_.add(description(index));
    g_signal_connect(h->base, "handle-ioctl", reinterpret_cast<GCallback>(&FakeHidDevice::on_ioctl), h);
    g_signal_connect(h->base, "handle-write", reinterpret_cast<GCallback>(&FakeHidDevice::on_write), h);
    GError* err = nullptr;
    if (!umockdev_testbed_attach_ioctl(tb_.get(), h->node.c_str(), h->base, &err)) {
        std::string msg = err ? err->message : "?";
        g_clear_error(&err);
        throw std::runtime_error("umockdev: cannot attach to " + h->node + ": " + msg);
    }
    // The node is a pty: make it a raw, non-blocking byte pipe so binary reports pass unchanged.
    const int fd = umockdev_testbed_get_dev_fd(tb_.get(), h->node.c_str());
    if (fd < 0) throw std::runtime_error("umockdev: no pty behind " + h->node);
    termios tio{};
    tcgetattr(fd, &tio);
    cfmakeraw(&tio);
    tcsetattr(fd, TCSANOW, &tio);
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
    {
        std::lock_guard lock(m_);
        master_fd_ = fd;
        present_ = true;
    }
    if (!pump_.joinable()) pump_ = std::thread([this] { pump(); });
}

void FakeHidDevice::unplug() {
    std::string hid;
    {
        std::lock_guard lock(m_);
        if (!present_) return;
        present_ = false;
        master_fd_ = -1;
        hid = hid_dir(generation_ - 1, vid_, pid_);
    }
    // the whole USB device goes: hidraw node, hid device, interface, device
    tb_.remove("/sys" + hid + "/hidraw/hidraw" + std::to_string(generation_ - 1));
    tb_.remove("/sys" + hid);
    tb_.remove("/sys/devices/pci0000:00/0000:00:14.0/usb1/1-2/1-2:1.0");
    tb_.remove("/sys/devices/pci0000:00/0000:00:14.0/usb1/1-2");
}

// Device → host: pack the endpoint's bytes into input reports and push them into the pty.
void FakeHidDevice::pump() {
    std::vector<std::uint8_t> backlog;
    std::size_t sent = 0;
    while (!stop_) {
        {
            std::lock_guard lock(m_);
            if (!present_) {
                backlog.clear();
                sent = 0;
            } else {
                if (sent == backlog.size()) {
                    backlog.clear();
                    sent = 0;
                    std::uint8_t buf[kHidPayloadMax * 16];
                    const std::size_t n = endpoint_.take_device_bytes(buf);
                    for (const auto& r : hid_pack_reports({buf, n})) backlog.insert(backlog.end(), r.begin(), r.end());
                }
                while (sent < backlog.size()) {
                    const ssize_t w = ::write(master_fd_, backlog.data() + sent, backlog.size() - sent);
                    if (w <= 0) break;  // the host is not reading: keep the rest for later
                    sent += static_cast<std::size_t>(w);
                }
            }
        }
        std::this_thread::sleep_for(std::chrono::microseconds(500));
    }
}

int FakeHidDevice::on_ioctl(void* /*handler*/, void* client, void* user_data) {
    auto* h = static_cast<Handle*>(user_data);
    auto* c = static_cast<UMockdevIoctlClient*>(client);
    const gulong req = umockdev_ioctl_client_get_request(c);
    UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(c);
    {
        std::lock_guard lock(h->dev->m_);
        if (!h->dev->present_ || h->generation != h->dev->generation_) {
            umockdev_ioctl_client_complete(c, -1, ENODEV);
            return TRUE;
        }
    }
    if (req == HIDIOCGRDESCSIZE) {
        UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, sizeof(int), nullptr);
        const int size = sizeof kReportDescriptor;
        std::memcpy(d->data, &size, sizeof size);
        umockdev_ioctl_client_complete(c, 0, 0);
        g_object_unref(d);
    } else if (req == HIDIOCGRDESC) {
        UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, sizeof(hidraw_report_descriptor), nullptr);
        auto* rd = reinterpret_cast<hidraw_report_descriptor*>(d->data);
        rd->size = sizeof kReportDescriptor;
        std::memcpy(rd->value, kReportDescriptor, sizeof kReportDescriptor);
        umockdev_ioctl_client_complete(c, 0, 0);
        g_object_unref(d);
    } else {
        umockdev_ioctl_client_complete(c, -1, ENOTTY);
    }
    return TRUE;
}

// Host → device: one write() is one output report, prefixed with report ID 0 (hidraw strips it).
int FakeHidDevice::on_write(void* /*handler*/, void* client, void* user_data) {
    auto* h = static_cast<Handle*>(user_data);
    auto* c = static_cast<UMockdevIoctlClient*>(client);
    UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(c);
    FakeHidDevice& dev = *h->dev;
    std::lock_guard lock(dev.m_);
    if (!dev.present_ || h->generation != dev.generation_) {
        umockdev_ioctl_client_complete(c, -1, ENODEV);
        return TRUE;
    }
    const std::uint8_t* p = arg->data;
    std::size_t n = arg->data_len;
    if (n > 0 && p[0] == 0) {
        ++p;
        --n;
    }
    if (n == kHidReportSize && p[0] <= kHidPayloadMax) {
        ++dev.reports_received_;
        dev.endpoint_.on_host_bytes({p + 1, p[0]});
    }
    umockdev_ioctl_client_complete(c, static_cast<glong>(arg->data_len), 0);
    return TRUE;
}

}  // namespace ballbar::device::testing
