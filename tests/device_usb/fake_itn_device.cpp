// SPDX-License-Identifier: MIT
#include "fake_itn_device.hpp"

// clang-format off
#include <sys/ioctl.h>  // before linux/usbdevice_fs.h
#include <linux/usbdevice_fs.h>
// clang-format on
#include <algorithm>
#include <cerrno>
#include <cstddef>
#include <cstring>
#include <stdexcept>

namespace ballbar::device::testing {

struct FakeItnDevice::Urb {
    UMockdevIoctlData* urb;
    UMockdevIoctlData* buf;
    int generation;
    usbdevfs_urb* u() const { return reinterpret_cast<usbdevfs_urb*>(urb->data); }
};

struct FakeItnDevice::Handle {
    FakeItnDevice* dev;
    int generation;
    std::string node;
    UMockdevIoctlBase* base;
};

namespace {

constexpr std::uint8_t kEpInItn = 0x81;
const char* const kItnManufacturer = "Mitutoyo";
const char* const kItnProduct = "USB-ITN";

void release_itn(FakeItnDevice::Urb* u);

}  // namespace

FakeItnDevice::FakeItnDevice(Testbed& tb, gauge::GaugeEmulator& emulator, std::string serial, int port)
    : tb_(tb), emu_(emulator), serial_(std::move(serial)), port_(port) {}

FakeItnDevice::~FakeItnDevice() {
    for (Handle* h : handles_) {
        umockdev_testbed_detach_ioctl(tb_.get(), h->node.c_str(), nullptr);
        g_object_unref(h->base);
        delete h;
    }
    for (Urb* u : pending_in_) release_itn(u);
    for (Urb* u : done_) release_itn(u);
}

std::string FakeItnDevice::node() const {
    std::lock_guard lock(m_);
    char buf[40];
    std::snprintf(buf, sizeof buf, "/dev/bus/usb/001/%03d", devnum_);
    return buf;
}

std::string FakeItnDevice::syspath() const {
    return "/sys/devices/pci0000:00/0000:00:14.0/usb1/1-" + std::to_string(port_);
}

int FakeItnDevice::in_transfers() const {
    std::lock_guard lock(m_);
    return in_transfers_;
}

int FakeItnDevice::vendor_requests() const {
    std::lock_guard lock(m_);
    return vendor_requests_;
}

std::string FakeItnDevice::description() const {
    constexpr std::uint16_t vid_ = gauge::kItnVendorId;
    constexpr std::uint16_t pid_ = gauge::kItnProductId;
    const std::uint8_t descriptors[] = {
        // device: USB 2.0, class per interface, EP0 64 bytes, VID, PID, bcdDevice 1.00, strings 1/2/3, 1 config
        0x12, 0x01, 0x00, 0x02, 0x00, 0x00, 0x00, 0x40, static_cast<std::uint8_t>(vid_ & 0xff),
        static_cast<std::uint8_t>(vid_ >> 8), static_cast<std::uint8_t>(pid_ & 0xff),
        static_cast<std::uint8_t>(pid_ >> 8), 0x00, 0x01, 0x01, 0x02, 0x03, 0x01,
        // configuration 1: one interface, bus powered, 100 mA
        0x09, 0x02, 0x22, 0x00, 0x01, 0x01, 0x00, 0x80, 0x32,
        // interface 0: HID (a boot keyboard by default), one endpoint
        0x09, 0x04, 0x00, 0x00, 0x01, 0x03, 0x01, 0x01, 0x00,
        // HID descriptor: HID 1.11, one report descriptor of 63 bytes
        0x09, 0x21, 0x11, 0x01, 0x00, 0x01, 0x22, 0x3f, 0x00,
        // interrupt IN 0x81, 8-byte reports, every 10 ms
        0x07, 0x05, kEpInItn, 0x03, 0x08, 0x00, 0x0a};
    char vp[16];
    std::snprintf(vp, sizeof vp, "%04x/%x/100", vid_, pid_);
    char num[8];
    std::snprintf(num, sizeof num, "%03d", devnum_);
    std::string d;
    d += "P: " + syspath().substr(4) + "\n";  // without the /sys prefix
    d += std::string("N: bus/usb/001/") + num + "\n";
    d += "E: SUBSYSTEM=usb\nE: DEVTYPE=usb_device\n";
    d += std::string("E: DEVNAME=/dev/bus/usb/001/") + num + "\n";
    d += std::string("E: BUSNUM=001\nE: DEVNUM=") + num + "\n";
    d += std::string("E: PRODUCT=") + vp + "\nE: DRIVER=usb\n";
    char ids[64];
    std::snprintf(ids, sizeof ids, "A: idVendor=%04x\\n\nA: idProduct=%04x\\n\n", vid_, pid_);
    d += ids;
    d += "A: busnum=1\\n\nA: devnum=" + std::to_string(devnum_) + "\\n\n";
    d += "A: speed=12\\n\nA: bcdDevice=0100\\n\nA: bConfigurationValue=1\\n\nA: bNumConfigurations=1\\n\n";
    d += "A: bDeviceClass=00\\n\nA: bMaxPacketSize0=64\\n\n";
    d += std::string("A: manufacturer=") + kItnManufacturer + "\\n\n";
    d += std::string("A: product=") + kItnProduct + "\\n\n";
    d += "A: serial=" + serial_ + "\\n\n";
    d += "A: dev=189:" + std::to_string(devnum_ - 1) + "\\n\n";
    d += "A: devpath=" + std::to_string(port_) + "\\n\n";
    d += "H: descriptors=" + to_hex(descriptors) + "\n";
    return d;
}

void FakeItnDevice::plug() {
    std::string node_path;
    Handle* h = nullptr;
    {
        std::lock_guard lock(m_);
        if (present_) return;
        ++devnum_;  // a replugged device gets a new address, as on a real bus
        ++generation_;
        present_ = true;
        char buf[40];
        std::snprintf(buf, sizeof buf, "/dev/bus/usb/001/%03d", devnum_);
        node_path = buf;
        h = new Handle{this, generation_, node_path, umockdev_ioctl_base_new()};
        handles_.push_back(h);
    }
    tb_.add(description());
    g_signal_connect(h->base, "handle-ioctl", reinterpret_cast<GCallback>(&FakeItnDevice::on_ioctl), h);
    GError* err = nullptr;
    if (!umockdev_testbed_attach_ioctl(tb_.get(), node_path.c_str(), h->base, &err)) {
        std::string msg = err ? err->message : "?";
        g_clear_error(&err);
        throw std::runtime_error("umockdev: cannot attach ioctl handler to " + node_path + ": " + msg);
    }
}

void FakeItnDevice::unplug() {
    {
        std::lock_guard lock(m_);
        if (!present_) return;
        present_ = false;
        while (!pending_in_.empty()) {
            complete_locked(pending_in_.front(), -ESHUTDOWN, 0);
            pending_in_.pop_front();
        }
    }
    tb_.remove(syspath());
}

void FakeItnDevice::complete_locked(Urb* u, int status, int length) {
    u->u()->status = status;
    u->u()->actual_length = length;
    done_.push_back(u);
}

// Feeds queued IN transfers from the endpoint's pending bytes.
void FakeItnDevice::pump_locked() {
    while (present_ && !pending_in_.empty()) {
        Urb* u = pending_in_.front();
        const auto len = static_cast<std::size_t>(u->u()->buffer_length);
        const std::size_t n = emu_.take_interrupt({u->buf->data, len});
        if (n == 0) return;
        pending_in_.pop_front();
        ++in_transfers_;
        complete_locked(u, 0, static_cast<int>(n));
    }
}

// The ITN's vendor requests and GET_DESCRIPTOR(STRING); anything else stalls. Returns the data-stage
// length or -errno.
int FakeItnDevice::control_locked(Urb* u) {
    std::uint8_t* b = u->buf->data;
    const int wlength = b[6] | b[7] << 8;
    const auto wvalue = static_cast<std::uint16_t>(b[2] | b[3] << 8);
    if (b[0] == 0x40) {
        ++vendor_requests_;
        emu_.control_out(b[1], wvalue, {b + 8, static_cast<std::size_t>(wlength)});
        return wlength;
    }
    if (b[0] == 0xC0) {
        ++vendor_requests_;
        const int n = emu_.control_in(b[1], wvalue, {b + 8, static_cast<std::size_t>(wlength)});
        return n < 0 ? -EPIPE : n;
    }
    if (b[0] != 0x80 || b[1] != 6 || b[3] != 3) return -EPIPE;
    std::uint8_t d[255];
    int n = 2;
    const int index = b[2];
    if (index == 0) {
        d[2] = 0x09;  // LANGID en-US
        d[3] = 0x04;
        n = 4;
    } else {
        const std::string s = index == 1 ? kItnManufacturer : index == 2 ? kItnProduct : index == 3 ? serial_ : "";
        if (index > 3) return -EPIPE;
        for (char c : s) {
            d[n++] = static_cast<std::uint8_t>(c);
            d[n++] = 0;
        }
    }
    d[0] = static_cast<std::uint8_t>(n);
    d[1] = 3;
    n = std::min(n, wlength);
    std::memcpy(b + 8, d, static_cast<std::size_t>(n));
    return n;  // actual_length excludes the 8 setup bytes
}

namespace {

void release_itn(FakeItnDevice::Urb* u) {
    g_object_unref(u->buf);
    g_object_unref(u->urb);
    delete u;
}

void complete_itn(UMockdevIoctlClient* c, long result, int err) {
    umockdev_ioctl_client_complete(c, result, err);
}

}  // namespace

int FakeItnDevice::on_ioctl(void* /*handler*/, void* client, void* user_data) {
    auto* h = static_cast<Handle*>(user_data);
    auto* c = static_cast<UMockdevIoctlClient*>(client);
    FakeItnDevice& dev = *h->dev;
    const gulong req = umockdev_ioctl_client_get_request(c);
    UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(c);
    std::lock_guard lock(dev.m_);
    const bool alive = dev.present_ && h->generation == dev.generation_;

    if (req == USBDEVFS_REAPURB || req == USBDEVFS_REAPURBNDELAY) {
        if (alive) dev.pump_locked();
        // Only URBs submitted through this plug's node (an older plug's were all completed at unplug).
        auto it = std::find_if(dev.done_.begin(), dev.done_.end(),
                               [h](const Urb* x) { return x->generation == h->generation; });
        if (it == dev.done_.end()) {
            complete_itn(c, -1, alive ? EAGAIN : ENODEV);
            return TRUE;
        }
        Urb* u = *it;
        dev.done_.erase(it);
        UMockdevIoctlData* slot = umockdev_ioctl_data_resolve(arg, 0, sizeof(void*), nullptr);
        umockdev_ioctl_data_set_ptr(slot, 0, u->urb);  // *arg = the client's urb pointer
        complete_itn(c, 0, 0);                         // syncs urb + buffer back to the client
        g_object_unref(slot);
        release_itn(u);
        return TRUE;
    }
    if (!alive) {
        complete_itn(c, -1, ENODEV);
        return TRUE;
    }
    switch (req) {
        case USBDEVFS_GET_CAPABILITIES: {
            UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, 4, nullptr);
            const std::uint32_t caps = USBDEVFS_CAP_NO_PACKET_SIZE_LIM | USBDEVFS_CAP_ZERO_PACKET;
            std::memcpy(d->data, &caps, sizeof caps);
            complete_itn(c, 0, 0);
            g_object_unref(d);
            return TRUE;
        }
        case USBDEVFS_CLAIMINTERFACE:
        case USBDEVFS_RELEASEINTERFACE:
        case USBDEVFS_DISCONNECT_CLAIM:
        case USBDEVFS_CLEAR_HALT:
        case USBDEVFS_RESET:
        case USBDEVFS_SETINTERFACE:
            complete_itn(c, 0, 0);
            return TRUE;
        case USBDEVFS_SUBMITURB: {
            auto* u =
                new Urb{umockdev_ioctl_data_resolve(arg, 0, sizeof(usbdevfs_urb), nullptr), nullptr, h->generation};
            u->buf = umockdev_ioctl_data_resolve(u->urb, offsetof(usbdevfs_urb, buffer),
                                                 static_cast<gsize>(u->u()->buffer_length), nullptr);
            usbdevfs_urb* urb = u->u();
            if (urb->type == USBDEVFS_URB_TYPE_CONTROL) {
                const int r = dev.control_locked(u);
                dev.complete_locked(u, r < 0 ? r : 0, r < 0 ? 0 : r);
            } else if (urb->type == USBDEVFS_URB_TYPE_INTERRUPT && urb->endpoint == kEpInItn) {
                dev.pending_in_.push_back(u);
            } else {
                release_itn(u);
                complete_itn(c, -1, EINVAL);
                return TRUE;
            }
            dev.pump_locked();
            complete_itn(c, 0, 0);
            return TRUE;
        }
        case USBDEVFS_DISCARDURB: {  // arg is the client's address of the URB
            for (auto it = dev.pending_in_.begin(); it != dev.pending_in_.end(); ++it) {
                if ((*it)->urb->client_addr == *reinterpret_cast<gulong*>(arg->data)) {
                    Urb* u = *it;
                    dev.pending_in_.erase(it);
                    dev.complete_locked(u, -ENOENT, 0);
                    complete_itn(c, 0, 0);
                    return TRUE;
                }
            }
            complete_itn(c, -1, EINVAL);
            return TRUE;
        }
        default:
            complete_itn(c, -1, ENOTTY);
            return TRUE;
    }
}

}  // namespace ballbar::device::testing
