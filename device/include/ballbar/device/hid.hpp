// SPDX-License-Identifier: MIT
// The HID link (hidapi, hidraw backend): 64-byte reports carrying the protocol's byte stream.
// Report layout (docs/device.md, "HID reports"): byte 0 = number of payload bytes n (0..63),
// bytes 1..n = the next n bytes of the stream, the rest zero. No report IDs.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "ballbar/device/transport.hpp"

namespace ballbar::device {

inline constexpr std::size_t kHidReportSize = 64;
inline constexpr std::size_t kHidPayloadMax = kHidReportSize - 1;

/// Opens the first HID device vid:pid (whose serial-number string equals `serial` unless it is empty)
/// through hidraw. URI of the result: "hid:VVVV:PPPP:SERIAL".
/// Throws DeviceError: NotFound, Permission (udev rules missing: the message says how to install them),
/// Io. Reads/writes throw Disconnected once the device is unplugged; opening again later works.
std::unique_ptr<Transport> open_hid_transport(std::uint16_t vid, std::uint16_t pid, const std::string& serial);

/// Splits a byte stream into 64-byte reports (byte 0 = payload length). Pure; used by the transport
/// and by the device side of the HID link (tests, emulator hosting).
std::vector<std::array<std::uint8_t, kHidReportSize>> hid_pack_reports(std::span<const std::uint8_t> data);

/// The payload of one 64-byte report; throws DeviceError{Protocol} if its length byte exceeds 63.
std::span<const std::uint8_t> hid_report_payload(std::span<const std::uint8_t, kHidReportSize> report);

}  // namespace ballbar::device
