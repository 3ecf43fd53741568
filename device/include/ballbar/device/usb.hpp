// SPDX-License-Identifier: MIT
// The USB bulk link (libusb-1.0): our instrument's vendor-class interface with one bulk IN and one
// bulk OUT endpoint, carrying the protocol's byte stream unchanged (docs/device.md, "USB bulk").
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "ballbar/device/transport.hpp"

namespace ballbar::device {

/// Opens the first USB device vid:pid (whose serial-number string equals `serial` unless it is empty),
/// claims its vendor interface and returns a Transport over its bulk endpoints. URI of the result:
/// "usb:VVVV:PPPP:SERIAL" (lower-case hex).
/// Throws DeviceError: NotFound (no such device), Permission (the device node may not be opened:
/// the message says how to install the udev rules), Disconnected (it vanished while opening), Io.
/// Reads/writes throw Disconnected once the device is unplugged; opening again later works.
std::unique_ptr<Transport> open_usb_transport(std::uint16_t vid, std::uint16_t pid, const std::string& serial);

/// The message of a DeviceError{Permission} for `node`: says the udev rules are missing and how to
/// install them. Shared by the USB, HID and serial links.
std::string udev_permission_hint(const std::string& node);

}  // namespace ballbar::device
