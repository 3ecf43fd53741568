// SPDX-License-Identifier: MIT
// USB bulk link over libusb-1.0: one context per transport, synchronous bulk transfers.
#include <libusb-1.0/libusb.h>

#include <algorithm>
#include <atomic>
#include <climits>
#include <cstring>
#include <vector>

#include "ballbar/device/ids.hpp"
#include "ballbar/device/usb.hpp"

namespace ballbar::device {

std::string udev_permission_hint(const std::string& node) {
    return "permission denied on " + node +
           ": the ballbar udev rules are missing or not applied. Install them with "
           "`sudo cmake --install build --component udev` (rules go to <prefix>/lib/udev/rules.d; udev reads "
           "/usr/lib/udev/rules.d and /etc/udev/rules.d, so configure with -DCMAKE_INSTALL_PREFIX=/usr or "
           "-DBALLBAR_UDEV_RULES_DIR=/etc/udev/rules.d, or copy udev/70-ballbar.rules to /etc/udev/rules.d/), "
           "then run `sudo udevadm control --reload && sudo udevadm trigger` and replug the instrument";
}

namespace {

constexpr std::size_t kInBufferSize = 4096;  // a multiple of every bulk max packet size (64, 512, 1024)

std::string usb_name(std::uint16_t vid, std::uint16_t pid) {
    return hex4(vid) + ":" + hex4(pid);
}

std::string libusb_text(int rc) {
    return std::string(libusb_error_name(rc)) + " (" + libusb_strerror(static_cast<libusb_error>(rc)) + ")";
}

unsigned int to_libusb_timeout(std::chrono::milliseconds timeout) {
    // libusb treats 0 as "wait forever"; our 0 means "poll".
    const auto ms = std::max<std::chrono::milliseconds::rep>(1, timeout.count());
    return static_cast<unsigned int>(std::min<std::chrono::milliseconds::rep>(ms, UINT_MAX));
}

std::string node_path(libusb_device* dev) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "/dev/bus/usb/%03u/%03u", static_cast<unsigned>(libusb_get_bus_number(dev)),
                  static_cast<unsigned>(libusb_get_device_address(dev)));
    return buf;
}

struct Endpoints {
    int interface = -1;
    int altsetting = 0;
    std::uint8_t in = 0;
    std::uint8_t out = 0;
    std::size_t in_packet = 64;
};

/// The first vendor-class interface with a bulk IN and a bulk OUT endpoint.
Endpoints find_vendor_bulk(libusb_device* dev) {
    libusb_config_descriptor* cfg = nullptr;
    if (libusb_get_active_config_descriptor(dev, &cfg) != 0 && libusb_get_config_descriptor(dev, 0, &cfg) != 0) {
        return {};
    }
    Endpoints found;
    for (int i = 0; i < cfg->bNumInterfaces && found.interface < 0; ++i) {
        const libusb_interface& itf = cfg->interface[i];
        for (int a = 0; a < itf.num_altsetting && found.interface < 0; ++a) {
            const libusb_interface_descriptor& alt = itf.altsetting[a];
            if (alt.bInterfaceClass != LIBUSB_CLASS_VENDOR_SPEC) continue;
            Endpoints e;
            for (int k = 0; k < alt.bNumEndpoints; ++k) {
                const libusb_endpoint_descriptor& ep = alt.endpoint[k];
                if ((ep.bmAttributes & 0x03) != LIBUSB_TRANSFER_TYPE_BULK) continue;
                if ((ep.bEndpointAddress & LIBUSB_ENDPOINT_IN) != 0) {
                    if (e.in == 0) {
                        e.in = ep.bEndpointAddress;
                        e.in_packet = std::max<std::size_t>(ep.wMaxPacketSize & 0x7ff, 8);
                    }
                } else if (e.out == 0) {
                    e.out = ep.bEndpointAddress;
                }
            }
            if (e.in != 0 && e.out != 0) {
                e.interface = alt.bInterfaceNumber;
                e.altsetting = alt.bAlternateSetting;
                found = e;
            }
        }
    }
    libusb_free_config_descriptor(cfg);
    return found;
}

std::string read_serial(libusb_device_handle* h, const libusb_device_descriptor& dd) {
    if (dd.iSerialNumber == 0) return {};
    unsigned char buf[128];
    const int n = libusb_get_string_descriptor_ascii(h, dd.iSerialNumber, buf, sizeof buf);
    if (n <= 0) return {};
    return std::string(reinterpret_cast<const char*>(buf), static_cast<std::size_t>(n));
}

class UsbTransport final : public Transport {
  public:
    UsbTransport(libusb_context* ctx, libusb_device_handle* handle, Endpoints ep, std::string uri, std::string node)
        : ctx_(ctx), handle_(handle), ep_(ep), uri_(std::move(uri)), node_(std::move(node)), in_buf_(kInBufferSize) {}

    ~UsbTransport() override {
        if (!gone_) libusb_release_interface(handle_, ep_.interface);
        libusb_close(handle_);
        libusb_exit(ctx_);
    }
    UsbTransport(const UsbTransport&) = delete;
    UsbTransport& operator=(const UsbTransport&) = delete;

    void write(std::span<const std::uint8_t> data, std::chrono::milliseconds timeout) override {
        check_present();
        std::size_t sent = 0;
        while (sent < data.size()) {
            const std::size_t chunk = std::min<std::size_t>(data.size() - sent, 1U << 16);
            int done = 0;
            // libusb takes a non-const buffer for both directions; OUT transfers do not modify it.
            auto* p = const_cast<unsigned char*>(data.data() + sent);
            const int rc =
                libusb_bulk_transfer(handle_, ep_.out, p, static_cast<int>(chunk), &done, to_libusb_timeout(timeout));
            sent += static_cast<std::size_t>(std::max(done, 0));
            if (rc == LIBUSB_ERROR_TIMEOUT) {
                throw DeviceError(DeviceErrorKind::Timeout, uri_ + ": bulk OUT timed out after " +
                                                                std::to_string(sent) + " of " +
                                                                std::to_string(data.size()) + " bytes");
            }
            if (rc != 0) fail(rc, "bulk OUT");
        }
    }

    std::size_t read(std::span<std::uint8_t> data, std::chrono::milliseconds timeout) override {
        if (data.empty()) return 0;
        if (in_pos_ == in_len_) {
            check_present();
            int got = 0;
            const int rc = libusb_bulk_transfer(handle_, ep_.in, in_buf_.data(), static_cast<int>(in_buf_.size()), &got,
                                                to_libusb_timeout(timeout));
            if (rc != 0 && rc != LIBUSB_ERROR_TIMEOUT) fail(rc, "bulk IN");
            in_pos_ = 0;
            in_len_ = static_cast<std::size_t>(std::max(got, 0));  // a timeout may still carry data
        }
        const std::size_t n = std::min(data.size(), in_len_ - in_pos_);
        std::memcpy(data.data(), in_buf_.data() + in_pos_, n);
        in_pos_ += n;
        return n;
    }

    std::string uri() const override { return uri_; }

  private:
    void check_present() const {
        if (gone_) throw DeviceError(DeviceErrorKind::Disconnected, uri_ + ": the USB device was disconnected");
    }

    [[noreturn]] void fail(int rc, const char* what) {
        if (rc == LIBUSB_ERROR_NO_DEVICE) {
            gone_ = true;
            throw DeviceError(DeviceErrorKind::Disconnected,
                              uri_ + ": the USB device was disconnected (" + what + ": " + libusb_text(rc) + ")");
        }
        if (rc == LIBUSB_ERROR_ACCESS) throw DeviceError(DeviceErrorKind::Permission, udev_permission_hint(node_));
        throw DeviceError(DeviceErrorKind::Io, uri_ + ": " + what + " failed: " + libusb_text(rc));
    }

    libusb_context* ctx_;
    libusb_device_handle* handle_;
    Endpoints ep_;
    std::string uri_;
    std::string node_;
    std::vector<std::uint8_t> in_buf_;
    std::size_t in_pos_ = 0;
    std::size_t in_len_ = 0;
    std::atomic<bool> gone_{false};  // set by the reader or the writer thread
};

struct ContextGuard {
    libusb_context* ctx = nullptr;
    ~ContextGuard() {
        if (ctx) libusb_exit(ctx);
    }
};

struct ListGuard {
    libusb_device** list = nullptr;
    ~ListGuard() {
        if (list) libusb_free_device_list(list, 1);
    }
};

}  // namespace

std::unique_ptr<Transport> open_usb_transport(std::uint16_t vid, std::uint16_t pid, const std::string& serial) {
    const std::string name = usb_name(vid, pid) + (serial.empty() ? "" : " with serial " + serial);
    ContextGuard ctx;
    if (int rc = libusb_init(&ctx.ctx); rc != 0) {
        ctx.ctx = nullptr;
        // typically: no usbfs on this machine (containers), so there is no such device to open
        throw DeviceError(DeviceErrorKind::NotFound,
                          "no USB device " + name + " found: USB is not available (libusb: " + libusb_text(rc) + ")");
    }
    ListGuard devices;
    const ssize_t count = libusb_get_device_list(ctx.ctx, &devices.list);
    if (count < 0) {
        throw DeviceError(DeviceErrorKind::Io, "cannot list USB devices: " + libusb_text(static_cast<int>(count)));
    }
    std::string denied_node;
    std::string other_error;
    for (ssize_t i = 0; i < count; ++i) {
        libusb_device* dev = devices.list[i];
        libusb_device_descriptor dd{};
        if (libusb_get_device_descriptor(dev, &dd) != 0 || dd.idVendor != vid || dd.idProduct != pid) continue;
        libusb_device_handle* h = nullptr;
        if (int rc = libusb_open(dev, &h); rc != 0) {
            if (rc == LIBUSB_ERROR_ACCESS) {
                denied_node = node_path(dev);
            } else {
                other_error = node_path(dev) + ": " + libusb_text(rc);
            }
            continue;
        }
        const std::string dev_serial = read_serial(h, dd);
        if (!serial.empty() && dev_serial != serial) {
            libusb_close(h);
            continue;
        }
        const Endpoints ep = find_vendor_bulk(dev);
        if (ep.interface < 0) {
            libusb_close(h);
            other_error = node_path(dev) + ": no vendor-class interface with bulk IN and OUT endpoints";
            continue;
        }
        libusb_set_auto_detach_kernel_driver(h, 1);  // LIBUSB_ERROR_NOT_SUPPORTED elsewhere is fine
        int rc = libusb_claim_interface(h, ep.interface);
        if (rc == 0 && ep.altsetting != 0) rc = libusb_set_interface_alt_setting(h, ep.interface, ep.altsetting);
        if (rc != 0) {
            libusb_close(h);
            const std::string node = node_path(dev);
            if (rc == LIBUSB_ERROR_ACCESS) throw DeviceError(DeviceErrorKind::Permission, udev_permission_hint(node));
            if (rc == LIBUSB_ERROR_NO_DEVICE) {
                throw DeviceError(DeviceErrorKind::Disconnected, node + ": the USB device vanished while opening");
            }
            if (rc == LIBUSB_ERROR_BUSY) {
                throw DeviceError(DeviceErrorKind::Io,
                                  node + ": interface " + std::to_string(ep.interface) +
                                      " is claimed by another program (is another ballbar running?)");
            }
            throw DeviceError(DeviceErrorKind::Io, node + ": cannot claim interface " + std::to_string(ep.interface) +
                                                       ": " + libusb_text(rc));
        }
        std::string uri = "usb:" + usb_name(vid, pid) + (dev_serial.empty() ? "" : ":" + dev_serial);
        auto t = std::make_unique<UsbTransport>(ctx.ctx, h, ep, std::move(uri), node_path(dev));
        ctx.ctx = nullptr;  // owned by the transport now
        return t;
    }
    if (!denied_node.empty()) throw DeviceError(DeviceErrorKind::Permission, udev_permission_hint(denied_node));
    if (!other_error.empty())
        throw DeviceError(DeviceErrorKind::Io, "cannot open USB device " + name + ": " + other_error);
    throw DeviceError(DeviceErrorKind::NotFound, "no USB device " + name + " found");
}

}  // namespace ballbar::device
