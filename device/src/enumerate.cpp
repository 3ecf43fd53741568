// SPDX-License-Identifier: MIT
#include "ballbar/device/enumerate.hpp"

#include <hidapi/hidapi.h>
#include <libserialport.h>
#include <libusb-1.0/libusb.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "wide_text.hpp"

namespace ballbar::device {
namespace {

std::string usb_uri(const char* scheme, std::uint16_t vid, std::uint16_t pid, const std::string& serial) {
    return std::string(scheme) + ":" + hex4(vid) + ":" + hex4(pid) + (serial.empty() ? "" : ":" + serial);
}

std::string ascii_string(libusb_device_handle* h, std::uint8_t index) {
    if (index == 0) return {};
    unsigned char buf[128];
    const int n = libusb_get_string_descriptor_ascii(h, index, buf, sizeof buf);
    return n > 0 ? std::string(reinterpret_cast<const char*>(buf), static_cast<std::size_t>(n)) : std::string();
}

void sort_from(std::vector<FoundInstrument>& v, std::size_t first) {
    std::sort(v.begin() + static_cast<std::ptrdiff_t>(first), v.end(),
              [](const FoundInstrument& a, const FoundInstrument& b) { return a.path < b.path; });
}

}  // namespace

void enumerate_serial(Enumeration& out) {
    sp_port** ports = nullptr;
    if (sp_list_ports(&ports) != SP_OK) {
        std::error_code ec;
        if (!std::filesystem::exists("/sys/class/tty", ec)) return;  // no ttys at all (containers)
        char* msg = sp_last_error_message();
        out.warnings.push_back(std::string("cannot list serial ports: ") + (msg ? msg : "?"));
        sp_free_error_message(msg);
        return;
    }
    const std::size_t first = out.instruments.size();
    for (sp_port** p = ports; *p; ++p) {
        if (sp_get_port_transport(*p) != SP_TRANSPORT_USB) continue;
        int vid = 0;
        int pid = 0;
        if (sp_get_port_usb_vid_pid(*p, &vid, &pid) != SP_OK) continue;
        const auto id = find_usb_id(static_cast<std::uint16_t>(vid), static_cast<std::uint16_t>(pid));
        if (!id || id->link != UsbLink::Serial) continue;
        FoundInstrument f;
        f.link = UsbLink::Serial;
        f.vid = id->vid;
        f.pid = id->pid;
        const char* product = sp_get_port_usb_product(*p);
        const char* serial = sp_get_port_usb_serial(*p);
        f.model = product && *product ? product : id->model;
        f.serial = serial ? serial : "";
        f.path = sp_get_port_name(*p);
        f.uri = "serial:" + f.path;
        out.instruments.push_back(std::move(f));
    }
    sp_free_port_list(ports);
    sort_from(out.instruments, first);
}

void enumerate_usb(Enumeration& out) {
    libusb_context* ctx = nullptr;
    if (int rc = libusb_init(&ctx); rc != 0) {
        out.warnings.push_back(std::string("USB devices not searched: libusb: ") + libusb_error_name(rc) +
                               " (no usbfs on this machine?)");
        return;
    }
    libusb_device** list = nullptr;
    const ssize_t count = libusb_get_device_list(ctx, &list);
    if (count < 0) {
        out.warnings.push_back(std::string("cannot list USB devices: ") + libusb_error_name(static_cast<int>(count)));
        libusb_exit(ctx);
        return;
    }
    const std::size_t first = out.instruments.size();
    for (ssize_t i = 0; i < count; ++i) {
        libusb_device_descriptor dd{};
        if (libusb_get_device_descriptor(list[i], &dd) != 0) continue;
        const auto id = find_usb_id(dd.idVendor, dd.idProduct);
        if (!id || id->link != UsbLink::UsbBulk) continue;  // HID and CDC devices are listed by their own link
        FoundInstrument f;
        f.link = UsbLink::UsbBulk;
        f.vid = id->vid;
        f.pid = id->pid;
        char node[64];
        std::snprintf(node, sizeof node, "/dev/bus/usb/%03u/%03u",
                      static_cast<unsigned>(libusb_get_bus_number(list[i])),
                      static_cast<unsigned>(libusb_get_device_address(list[i])));
        f.path = node;
        libusb_device_handle* h = nullptr;
        if (int rc = libusb_open(list[i], &h); rc == 0) {
            f.model = ascii_string(h, dd.iProduct);
            f.serial = ascii_string(h, dd.iSerialNumber);
            libusb_close(h);
        } else if (rc == LIBUSB_ERROR_ACCESS) {
            f.note = "permission denied: udev rules missing (docs/device.md, \"udev rules\")";
        } else {
            f.note = std::string("cannot open: ") + libusb_error_name(rc);
        }
        if (f.model.empty()) f.model = id->model;
        f.uri = usb_uri("usb", f.vid, f.pid, f.serial);
        out.instruments.push_back(std::move(f));
    }
    libusb_free_device_list(list, 1);
    libusb_exit(ctx);
    sort_from(out.instruments, first);
}

void enumerate_hid(Enumeration& out) {
    if (hid_init() != 0) {
        out.warnings.push_back("HID devices not searched: hidapi: " + detail::narrow(hid_error(nullptr)));
        return;
    }
    const std::size_t first = out.instruments.size();
    hid_device_info* list = hid_enumerate(kBallbarVendorId, 0);
    for (hid_device_info* i = list; i; i = i->next) {
        const auto id = find_usb_id(i->vendor_id, i->product_id);
        if (!id || id->link != UsbLink::Hid) continue;
        FoundInstrument f;
        f.link = UsbLink::Hid;
        f.vid = id->vid;
        f.pid = id->pid;
        f.model = detail::narrow(i->product_string);
        if (f.model.empty()) f.model = id->model;
        f.serial = detail::narrow(i->serial_number);
        f.path = i->path ? i->path : "";
        f.uri = usb_uri("hid", f.vid, f.pid, f.serial);
        out.instruments.push_back(std::move(f));
    }
    hid_free_enumeration(list);
    sort_from(out.instruments, first);
}

Enumeration enumerate_instruments() {
    Enumeration e;
    enumerate_serial(e);
    enumerate_usb(e);
    enumerate_hid(e);
    enumerate_gauges(e);
    return e;
}

}  // namespace ballbar::device
