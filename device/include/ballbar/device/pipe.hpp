// SPDX-License-Identifier: MIT
// The in-process link: a Transport whose other end is an Emulator in the same process (tests, the
// demo, `emulator:` URIs). With Pacing::Simulated a read that finds nothing advances the emulator's
// clock by up to its timeout (in 1 ms steps), so an hour of streaming takes as long as the CPU needs and
// timeouts are counted in simulated time; with Pacing::RealTime the emulator follows the steady clock.
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include "ballbar/device/emulator.hpp"
#include "ballbar/device/transport.hpp"

namespace ballbar::device {

enum class Pacing { Simulated, RealTime };

class PipeTransport : public Transport {
  public:
    /// Borrows `emulator` (it must outlive the transport).
    explicit PipeTransport(Emulator& emulator, Pacing pacing = Pacing::Simulated, std::string uri = "emulator:");
    /// Owns its emulator.
    explicit PipeTransport(std::unique_ptr<Emulator> emulator, Pacing pacing = Pacing::Simulated,
                           std::string uri = "emulator:");

    void write(std::span<const std::uint8_t> data, std::chrono::milliseconds timeout) override;
    std::size_t read(std::span<std::uint8_t> data, std::chrono::milliseconds timeout) override;
    std::string uri() const override { return uri_; }

    Emulator& emulator() { return *emulator_; }

  private:
    void check_connected() const;

    std::unique_ptr<Emulator> owned_;
    Emulator* emulator_;
    Pacing pacing_;
    std::string uri_;
    std::chrono::steady_clock::time_point start_;
    std::uint64_t start_us_;
};

}  // namespace ballbar::device
