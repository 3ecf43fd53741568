// SPDX-License-Identifier: MIT
// The emulator on a pseudo-terminal, served by a thread of this process on simulated time, for the
// demos (`demo`, `demo --test circular`): the session under demonstration talks to it through the
// real serial transport, codec and driver, as to a bar on a USB port.
#pragma once

#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "ballbar/device/emulator.hpp"
#include "ballbar/device/emulator_host.hpp"

namespace ballbar::workflow {

class PtyEmulator {
  public:
    /// `pacing`: simulated time (as fast as the session reads: the demos), or the wall clock (a machine
    /// driven by a real controller, which runs in real time).
    explicit PtyEmulator(device::EmulatorConfig config, device::Pacing pacing = device::Pacing::Simulated);
    ~PtyEmulator();
    PtyEmulator(const PtyEmulator&) = delete;
    PtyEmulator& operator=(const PtyEmulator&) = delete;
    /// Stops serving (the emulator's state can then be read without racing its thread).
    void halt();
    /// The current pty (a new one after a simulated disconnect); Error (device) when none opens in 10 s.
    std::string path();
    device::Emulator& emulator() { return emu_; }

  private:
    device::Emulator emu_;
    std::atomic<bool> stop_{false};
    std::unique_ptr<device::EmulatorHost> host_;
    std::thread thread_;
    std::mutex mutex_;
    std::condition_variable cv_;
    std::string path_, error_;
};

}  // namespace ballbar::workflow
