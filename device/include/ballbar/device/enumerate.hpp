// SPDX-License-Identifier: MIT
// Discovery of attached instruments (`ballbar devices`): USB CDC serial ports (libserialport), vendor
// bulk devices (libusb) and HID devices (hidapi), matched against the USB ID table (ids.hpp).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ballbar/device/ids.hpp"

namespace ballbar::device {

struct FoundInstrument {
    UsbLink link = UsbLink::Serial;
    std::uint16_t vid = 0;
    std::uint16_t pid = 0;
    std::string model;   ///< the product string it reports, else the table's model name
    std::string serial;  ///< empty when it cannot be read (see note)
    std::string path;    ///< device node: /dev/ttyACM0, /dev/bus/usb/001/002, /dev/hidraw0
    std::string uri;     ///< what `--device` takes: serial:PATH, usb:VID:PID[:SERIAL], hid:VID:PID[:SERIAL]
    std::string note;    ///< e.g. why the serial is unknown (permission: udev rules missing)
};

struct Enumeration {
    std::vector<FoundInstrument> instruments;  ///< serial, then USB, then HID; each sorted by path
    std::vector<std::string> warnings;         ///< a link that could not be searched, and why
};

/// Lists every attached instrument on all three links. Never throws for a missing subsystem
/// (no usbfs, no hidraw): that link contributes a warning and nothing else.
Enumeration enumerate_instruments();

void enumerate_serial(Enumeration& out);
void enumerate_usb(Enumeration& out);
void enumerate_hid(Enumeration& out);
/// The gauge cables of gauge_usb_ids() (URIs mitutoyo-itn:SERIAL, ...).
void enumerate_gauges(Enumeration& out);

}  // namespace ballbar::device
