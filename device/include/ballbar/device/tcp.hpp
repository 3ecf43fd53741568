// SPDX-License-Identifier: MIT
// TCP link: the instrument's byte stream over a socket, as ser2net serves a serial instrument, and as
// `ballbar emulate --tcp PORT` serves the emulator on loopback. URI "tcp:HOST:PORT".
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "ballbar/device/transport.hpp"

namespace ballbar::device {

/// Connects within `timeout`. Throws DeviceError: NotFound (unknown host, nothing listening), Timeout, Io.
/// Reads throw Disconnected when the peer closes the connection.
std::unique_ptr<Transport> open_tcp_transport(const std::string& host, std::uint16_t port,
                                              std::chrono::milliseconds timeout = std::chrono::milliseconds(3000));

}  // namespace ballbar::device
