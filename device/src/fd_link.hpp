// SPDX-License-Identifier: MIT
// Internal: poll(2)-based reads and writes on a byte-stream file descriptor (tty, pty, socket), with
// timeouts and the mapping of hang-ups to DeviceError{Disconnected}. Shared by the serial and TCP links.
#pragma once

#include <chrono>
#include <cstdint>
#include <span>
#include <string>

namespace ballbar::device::detail {

/// Reads at most data.size() bytes within `timeout`; 0 on timeout. Throws Disconnected on hang-up,
/// EOF or EIO/ENXIO/ENODEV/ECONNRESET; Io on anything else. `what` names the link in messages.
std::size_t fd_read(int fd, std::span<std::uint8_t> data, std::chrono::milliseconds timeout, const std::string& what);
/// Writes all of `data` within `timeout` (Timeout otherwise).
void fd_write(int fd, std::span<const std::uint8_t> data, std::chrono::milliseconds timeout, const std::string& what);

}  // namespace ballbar::device::detail
