// SPDX-License-Identifier: MIT
// Serial links: the instrument as a USB CDC-ACM port (/dev/ttyACM0), or the emulator behind a
// pseudo-terminal (`ballbar emulate --pty` → /dev/pts/N). docs/device.md explains the choice:
// libserialport opens and configures real ports (it finds them in sysfs, with their USB VID/PID and
// serial, and drives the modem lines); it refuses bare ptys, which we open with POSIX termios instead.
// Both end up as a file descriptor read and written with poll(2), so timeouts and disconnects behave
// the same way.
#pragma once

#include <memory>
#include <string>

#include "ballbar/device/transport.hpp"

namespace ballbar::device {

/// Opens `path` at `baud` 8N1, no flow control, DTR asserted. libserialport first; a pseudo-terminal
/// that libserialport refuses is opened with termios. URI of the result: "serial:PATH".
/// Throws DeviceError: NotFound (no such port), Permission (with how to install the udev rules), Io.
std::unique_ptr<Transport> open_serial_transport(const std::string& path, int baud = 115200);

/// The two ways in, for tests: libserialport only / termios only.
std::unique_ptr<Transport> open_libserialport_transport(const std::string& path, int baud = 115200);
std::unique_ptr<Transport> open_termios_transport(const std::string& path, int baud = 115200);

/// Character format of a serial line: baud, data bits (7 or 8), parity ('N', 'E', 'O'), stop bits (1 or 2).
struct SerialFormat {
    int baud = 115200;
    int data_bits = 8;
    char parity = 'N';
    int stop_bits = 1;
};

/// As above, with another character format (the gauges: Sylvac 4800 7E2, docs/instruments.md).
std::unique_ptr<Transport> open_serial_transport(const std::string& path, const SerialFormat& format);

std::unique_ptr<Transport> open_libserialport_format(const std::string& path, const SerialFormat& format);
std::unique_ptr<Transport> open_termios_format(const std::string& path, const SerialFormat& format);

/// True when `path` is a Unix 98 pseudo-terminal slave (major 136–143).
bool is_pseudo_terminal(const std::string& path);

}  // namespace ballbar::device
