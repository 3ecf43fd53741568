// SPDX-License-Identifier: MIT
// The USB-ITN's USB side over libusb-1.0: claim interface 0 (detaching the kernel's HID keyboard driver),
// vendor control transfers on endpoint 0 and synchronous interrupt-IN transfers.
#include <libusb-1.0/libusb.h>

#include <algorithm>
#include <climits>
#include <cstdio>

#include "ballbar/device/gauge.hpp"
#include "ballbar/device/ids.hpp"
#include "ballbar/device/usb.hpp"

namespace ballbar::device::gauge {
namespace {

unsigned to_ms(std::chrono::milliseconds t) {
    return static_cast<unsigned>(std::clamp<std::chrono::milliseconds::rep>(t.count(), 1, INT_MAX));
}

std::string ascii(libusb_device_handle* h, std::uint8_t index) {
    if (index == 0) return {};
    unsigned char buf[128];
    const int n = libusb_get_string_descriptor_ascii(h, index, buf, sizeof buf);
    return n > 0 ? std::string(reinterpret_cast<const char*>(buf), static_cast<std::size_t>(n)) : std::string();
}

class LibusbItnLink final : public ItnLink {
  public:
    LibusbItnLink(libusb_context* ctx, libusb_device_handle* h, std::string serial, std::string product)
        : ctx_(ctx), h_(h), serial_(std::move(serial)), product_(std::move(product)) {}
    ~LibusbItnLink() override {
        libusb_release_interface(h_, 0);
        libusb_close(h_);
        libusb_exit(ctx_);
    }
    LibusbItnLink(const LibusbItnLink&) = delete;
    LibusbItnLink& operator=(const LibusbItnLink&) = delete;

    void control_out(std::uint8_t request, std::uint16_t value, std::span<const std::uint8_t> data,
                     std::chrono::milliseconds timeout) override {
        auto* p = const_cast<unsigned char*>(data.data());  // OUT: libusb does not write to it
        const int rc = libusb_control_transfer(h_, 0x40, request, value, 0, p, static_cast<std::uint16_t>(data.size()),
                                               to_ms(timeout));
        if (rc < 0) fail(rc, "control OUT");
    }

    std::size_t control_in(std::uint8_t request, std::uint16_t value, std::span<std::uint8_t> data,
                           std::chrono::milliseconds timeout) override {
        const int rc = libusb_control_transfer(h_, 0xC0, request, value, 0, data.data(),
                                               static_cast<std::uint16_t>(data.size()), to_ms(timeout));
        if (rc < 0) fail(rc, "control IN");
        return static_cast<std::size_t>(rc);
    }

    std::size_t interrupt_in(std::span<std::uint8_t> data, std::chrono::milliseconds timeout) override {
        int got = 0;
        const int rc = libusb_interrupt_transfer(h_, kItnInterruptEndpoint, data.data(), static_cast<int>(data.size()),
                                                 &got, to_ms(timeout));
        if (rc == LIBUSB_ERROR_TIMEOUT) return static_cast<std::size_t>(std::max(got, 0));
        if (rc != 0) fail(rc, "interrupt IN");
        return static_cast<std::size_t>(got);
    }

    std::string serial() const override { return serial_; }
    std::string product() const override { return product_; }
    std::string uri() const override { return "mitutoyo-itn:" + serial_; }

  private:
    [[noreturn]] void fail(int rc, const char* what) const {
        const std::string msg = uri() + ": " + what + ": " + libusb_error_name(rc);
        if (rc == LIBUSB_ERROR_NO_DEVICE) throw DeviceError(DeviceErrorKind::Disconnected, msg);
        if (rc == LIBUSB_ERROR_TIMEOUT) throw DeviceError(DeviceErrorKind::Timeout, msg);
        throw DeviceError(DeviceErrorKind::Io, msg);
    }

    libusb_context* ctx_;
    libusb_device_handle* h_;
    std::string serial_, product_;
};

}  // namespace

std::unique_ptr<ItnLink> open_itn_usb(const std::string& serial) {
    libusb_context* ctx = nullptr;
    if (const int rc = libusb_init(&ctx); rc != 0)
        throw DeviceError(DeviceErrorKind::Io, std::string("libusb: ") + libusb_error_name(rc));
    libusb_device** list = nullptr;
    const ssize_t count = libusb_get_device_list(ctx, &list);
    bool denied = false;
    std::string denied_node;
    for (ssize_t i = 0; i < count; ++i) {
        libusb_device_descriptor dd{};
        if (libusb_get_device_descriptor(list[i], &dd) != 0) continue;
        if (dd.idVendor != kItnVendorId || dd.idProduct != kItnProductId) continue;
        libusb_device_handle* h = nullptr;
        if (const int rc = libusb_open(list[i], &h); rc != 0) {
            if (rc == LIBUSB_ERROR_ACCESS) {
                denied = true;
                char node[64];
                std::snprintf(node, sizeof node, "/dev/bus/usb/%03u/%03u", libusb_get_bus_number(list[i]),
                              libusb_get_device_address(list[i]));
                denied_node = node;
            }
            continue;
        }
        const std::string sn = ascii(h, dd.iSerialNumber);
        if (!serial.empty() && sn != serial) {
            libusb_close(h);
            continue;
        }
        const std::string product = ascii(h, dd.iProduct);
        libusb_set_auto_detach_kernel_driver(h, 1);  // the cable is a HID keyboard until we take it
        if (const int rc = libusb_claim_interface(h, 0); rc != 0) {
            libusb_close(h);
            libusb_free_device_list(list, 1);
            libusb_exit(ctx);
            throw DeviceError(rc == LIBUSB_ERROR_ACCESS ? DeviceErrorKind::Permission : DeviceErrorKind::Io,
                              "mitutoyo-itn:" + sn + ": cannot claim interface 0: " + libusb_error_name(rc));
        }
        libusb_free_device_list(list, 1);
        return std::make_unique<LibusbItnLink>(ctx, h, sn, product);
    }
    if (count >= 0) libusb_free_device_list(list, 1);
    libusb_exit(ctx);
    if (denied) throw DeviceError(DeviceErrorKind::Permission, udev_permission_hint(denied_node));
    throw DeviceError(DeviceErrorKind::NotFound, "mitutoyo-itn:" + serial + ": no USB-ITN cable (" +
                                                     hex4(kItnVendorId) + ":" + hex4(kItnProductId) + ")" +
                                                     (serial.empty() ? "" : " with serial " + serial));
}

}  // namespace ballbar::device::gauge
