// SPDX-License-Identifier: MIT
// The one table of our instrument's USB IDs. Drivers, enumeration (`ballbar devices`) and the udev
// rules (udev/70-ballbar.rules, checked against this table by tests/device_usb) all use it.
// Until a USB ID is allocated we use the pid.codes test vendor 0x1209 with its test product IDs
// (docs/device.md, "USB IDs").
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace ballbar::device {

/// How an instrument presents itself on the USB bus.
enum class UsbLink {
    Serial,   ///< USB CDC-ACM serial port (/dev/ttyACM*), URI serial:PATH
    UsbBulk,  ///< vendor-class interface with bulk IN/OUT endpoints, URI usb:VID:PID[:SERIAL]
    Hid,      ///< USB HID, 64-byte reports (/dev/hidraw*), URI hid:VID:PID[:SERIAL]
};

/// "serial", "usb", "hid": the URI scheme of the link.
const char* to_string(UsbLink link);

struct UsbId {
    std::uint16_t vid;
    std::uint16_t pid;
    UsbLink link;
    const char* model;  ///< product name the instrument reports, e.g. "BallBar BB-1"
};

/// pid.codes' test vendor ID.
inline constexpr std::uint16_t kBallbarVendorId = 0x1209;
inline constexpr std::uint16_t kBallbarBulkProductId = 0x0001;
inline constexpr std::uint16_t kBallbarHidProductId = 0x0002;
inline constexpr std::uint16_t kBallbarSerialProductId = 0x0003;

/// Every USB ID of our instruments (one entry per link).
std::span<const UsbId> usb_ids();

/// The table entry for vid:pid, if it is one of ours.
std::optional<UsbId> find_usb_id(std::uint16_t vid, std::uint16_t pid);

/// The table entry for `link` (there is exactly one per link).
UsbId usb_id_for(UsbLink link);

/// A gauge cable we drive (docs/instruments.md), with the URI scheme that opens it and the udev
/// subsystem of the node the driver opens ("usb": libusb's /dev/bus/usb node, "tty": a serial port).
struct GaugeUsbId {
    std::uint16_t vid;
    std::uint16_t pid;
    const char* scheme;     ///< "mitutoyo-itn", ...
    const char* subsystem;  ///< "usb" or "tty"
    const char* model;
};

/// Every gauge cable with a USB ID of its own. Enumeration (`ballbar devices`) and the gauge udev rules
/// (udev/70-ballbar-gauges.rules, written by gauge_udev_rules() and checked by tests/device_usb) use it.
/// Adaptors on generic USB-serial bridges are not in it: they are opened by their port path.
std::span<const GaugeUsbId> gauge_usb_ids();
std::optional<GaugeUsbId> find_gauge_usb_id(std::uint16_t vid, std::uint16_t pid);

/// The text of udev/70-ballbar-gauges.rules (`plugdev`: the udev/plugdev/ variant), from gauge_usb_ids().
std::string gauge_udev_rules(bool plugdev);

/// Four lower-case hex digits, as in udev rules and URIs: 0x1209 -> "1209", 0xB0B0 -> "b0b0".
std::string hex4(std::uint16_t value);

}  // namespace ballbar::device
