// SPDX-License-Identifier: MIT
// Test support: a umockdev testbed (fake sysfs, udev and /dev nodes, active under the
// libumockdev-preload LD_PRELOAD) and an echoing DeviceEndpoint.
#pragma once

#include <umockdev.h>

#include <cstdint>
#include <deque>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "ballbar/device/transport.hpp"

namespace ballbar::device::testing {

/// Owns a UMockdevTestbed. Only one may exist at a time in a process (it sets $UMOCKDEV_DIR).
class Testbed {
  public:
    Testbed();
    ~Testbed();
    Testbed(const Testbed&) = delete;
    Testbed& operator=(const Testbed&) = delete;

    UMockdevTestbed* get() const { return tb_; }
    /// True when the preload library is active (tests skip themselves otherwise).
    static bool preload_active();
    /// Adds the devices described in umockdev's text format; throws std::runtime_error on a bad description.
    void add(const std::string& description);
    /// Sends a "remove" uevent and deletes the device's sysfs directory.
    void remove(const std::string& syspath);

  private:
    UMockdevTestbed* tb_;
};

/// A device endpoint that sends back what it receives (thread-safe). Until told to, it also keeps a
/// copy of everything the host sent.
class EchoEndpoint final : public DeviceEndpoint {
  public:
    void on_host_bytes(std::span<const std::uint8_t> data) override;
    std::size_t take_device_bytes(std::span<std::uint8_t> out) override;
    std::vector<std::uint8_t> received() const;
    /// While muted, received bytes are recorded but not echoed.
    void set_muted(bool muted);

  private:
    mutable std::mutex m_;
    std::deque<std::uint8_t> out_;
    std::vector<std::uint8_t> received_;
    bool muted_ = false;
};

/// Hex string of bytes, upper-case, for umockdev's "H:" lines.
std::string to_hex(std::span<const std::uint8_t> bytes);

}  // namespace ballbar::device::testing
