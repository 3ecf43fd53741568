// SPDX-License-Identifier: MIT
// Device URIs, as `--device` takes them:
//   emulator:[CONFIG.json]   the emulator in this process, in real time (defaults without a file)
//   serial:PATH              a serial port or the pty of `ballbar emulate --pty`
//   tcp:HOST:PORT            a raw TCP byte stream (ser2net, `ballbar emulate --tcp`)
//   usb:VID:PID[:SERIAL]     vendor-class USB device, hex IDs (libusb)
//   hid:VID:PID[:SERIAL]     HID device, hex IDs (hidapi)
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "ballbar/device/transport.hpp"

namespace ballbar::device {

struct DeviceUri {
    enum class Scheme { Emulator, Serial, Tcp, Usb, Hid };
    Scheme scheme = Scheme::Emulator;
    std::string path;  ///< emulator config file, serial port
    std::string host;
    std::uint16_t port = 0;
    std::uint16_t vid = 0, pid = 0;
    std::string serial;
};

/// Throws std::invalid_argument with what is wrong and the accepted forms.
DeviceUri parse_device_uri(std::string_view uri);

/// Opens the link a URI names. Throws std::invalid_argument (malformed URI) or DeviceError.
std::unique_ptr<Transport> open_transport(std::string_view uri);

}  // namespace ballbar::device
