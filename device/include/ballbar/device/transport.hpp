// SPDX-License-Identifier: MIT
// The byte links the instrument protocol runs over: host side (Transport) and device side
// (DeviceEndpoint, which the emulator implements). Serial, USB bulk, HID, TCP and in-process pipes all
// carry the same frames (docs/protocol.md).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>

namespace ballbar::device {

/// What went wrong on a link. `Disconnected` is recoverable: the instrument may come back.
enum class DeviceErrorKind {
    NotFound,      ///< no instrument at that URI
    Permission,    ///< the device node exists but we may not open it (udev rules missing)
    Disconnected,  ///< the cable was pulled / the device vanished mid-session
    Timeout,       ///< no answer in time
    Protocol,      ///< the instrument answered something we cannot accept
    Io,            ///< any other I/O failure
};

const char* to_string(DeviceErrorKind kind);

class DeviceError : public std::runtime_error {
  public:
    DeviceError(DeviceErrorKind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
    DeviceErrorKind kind() const { return kind_; }

  private:
    DeviceErrorKind kind_;
};

/// Host side of a link: bytes with timeouts. Implementations are not thread-safe; one reader and one
/// writer thread at most, or one thread doing both.
class Transport {
  public:
    virtual ~Transport() = default;
    /// Writes all of `data` or throws DeviceError.
    virtual void write(std::span<const std::uint8_t> data, std::chrono::milliseconds timeout) = 0;
    /// Reads at most data.size() bytes; returns how many (0 when the timeout passed with nothing).
    /// Throws DeviceError{Disconnected} when the link is gone.
    virtual std::size_t read(std::span<std::uint8_t> data, std::chrono::milliseconds timeout) = 0;
    /// "serial:/dev/ttyACM0", "usb:1209:b0b0:0042", ...
    virtual std::string uri() const = 0;
};

/// Device side of a link: the emulated instrument receives the host's bytes and produces its own.
class DeviceEndpoint {
  public:
    virtual ~DeviceEndpoint() = default;
    /// Bytes the host wrote.
    virtual void on_host_bytes(std::span<const std::uint8_t> data) = 0;
    /// Copies up to out.size() pending device→host bytes into `out`, returns how many; never blocks.
    virtual std::size_t take_device_bytes(std::span<std::uint8_t> out) = 0;
};

}  // namespace ballbar::device
