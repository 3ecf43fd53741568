// SPDX-License-Identifier: MIT
// `ballbar devices`: the gauge cables with USB IDs of their own (gauge_usb_ids()).
#include <libserialport.h>
#include <libusb-1.0/libusb.h>

#include <cstdio>

#include "ballbar/device/enumerate.hpp"

namespace ballbar::device {

void enumerate_gauges(Enumeration& out) {
    // Serial gauge cables (none in the table today; the loop keeps the table the only place to add one).
    sp_port** ports = nullptr;
    if (sp_list_ports(&ports) == SP_OK) {
        for (sp_port** p = ports; *p; ++p) {
            int vid = 0, pid = 0;
            if (sp_get_port_transport(*p) != SP_TRANSPORT_USB || sp_get_port_usb_vid_pid(*p, &vid, &pid) != SP_OK)
                continue;
            const auto id = find_gauge_usb_id(static_cast<std::uint16_t>(vid), static_cast<std::uint16_t>(pid));
            if (!id || std::string(id->subsystem) != "tty") continue;
            FoundInstrument f;
            f.link = UsbLink::Serial;
            f.vid = id->vid;
            f.pid = id->pid;
            f.model = id->model;
            const char* serial = sp_get_port_usb_serial(*p);
            f.serial = serial ? serial : "";
            f.path = sp_get_port_name(*p);
            f.uri = std::string(id->scheme) + ":" + f.path;
            out.instruments.push_back(std::move(f));
        }
        sp_free_port_list(ports);
    }
    libusb_context* ctx = nullptr;
    if (libusb_init(&ctx) != 0) return;  // enumerate_usb already warned
    libusb_device** list = nullptr;
    const ssize_t count = libusb_get_device_list(ctx, &list);
    for (ssize_t i = 0; i < count; ++i) {
        libusb_device_descriptor dd{};
        if (libusb_get_device_descriptor(list[i], &dd) != 0) continue;
        const auto id = find_gauge_usb_id(dd.idVendor, dd.idProduct);
        if (!id || std::string(id->subsystem) != "usb") continue;
        FoundInstrument f;
        f.link = UsbLink::UsbBulk;
        f.vid = id->vid;
        f.pid = id->pid;
        char node[64];
        std::snprintf(node, sizeof node, "/dev/bus/usb/%03u/%03u", libusb_get_bus_number(list[i]),
                      libusb_get_device_address(list[i]));
        f.path = node;
        libusb_device_handle* h = nullptr;
        if (const int rc = libusb_open(list[i], &h); rc == 0) {
            unsigned char buf[128];
            if (dd.iSerialNumber != 0) {
                const int n = libusb_get_string_descriptor_ascii(h, dd.iSerialNumber, buf, sizeof buf);
                if (n > 0) f.serial.assign(reinterpret_cast<const char*>(buf), static_cast<std::size_t>(n));
            }
            if (dd.iProduct != 0) {
                const int n = libusb_get_string_descriptor_ascii(h, dd.iProduct, buf, sizeof buf);
                if (n > 0) f.model.assign(reinterpret_cast<const char*>(buf), static_cast<std::size_t>(n));
            }
            libusb_close(h);
        } else if (rc == LIBUSB_ERROR_ACCESS) {
            f.note = "permission denied: udev rules missing (docs/instruments.md, \"udev rules\")";
        } else {
            f.note = std::string("cannot open: ") + libusb_error_name(rc);
        }
        if (f.model.empty()) f.model = id->model;
        f.uri = std::string(id->scheme) + ":" + f.serial;
        out.instruments.push_back(std::move(f));
    }
    if (count >= 0) libusb_free_device_list(list, 1);
    libusb_exit(ctx);
}

}  // namespace ballbar::device
