// SPDX-License-Identifier: MIT
// The emulator as the device model of a fake USB/HID device: umockdev calls it from its worker thread
// (and the HID pump from another), so every call takes a lock; its clock follows the steady clock.
#pragma once

#include <chrono>
#include <mutex>

#include "ballbar/device/emulator.hpp"

namespace ballbar::device::testing {

class RealTimeEmulator final : public DeviceEndpoint {
  public:
    explicit RealTimeEmulator(EmulatorConfig config)
        : emu_(std::move(config)), start_(std::chrono::steady_clock::now()) {}

    void on_host_bytes(std::span<const std::uint8_t> data) override {
        std::lock_guard lock(m_);
        advance();
        emu_.on_host_bytes(data);
    }
    std::size_t take_device_bytes(std::span<std::uint8_t> out) override {
        std::lock_guard lock(m_);
        advance();
        return emu_.take_device_bytes(out);
    }
    /// Runs f(Emulator&) under the lock (to read counters or change faults).
    template <class F>
    auto with(F f) {
        std::lock_guard lock(m_);
        return f(emu_);
    }

  private:
    void advance() {
        const auto us =
            std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - start_);
        emu_.advance_to(static_cast<std::uint64_t>(us.count()));
    }

    std::mutex m_;
    Emulator emu_;
    std::chrono::steady_clock::time_point start_;
};

}  // namespace ballbar::device::testing
