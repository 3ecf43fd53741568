// SPDX-License-Identifier: MIT
#include "ballbar/workflow/pty_emulator.hpp"

#include <chrono>
#include <exception>
#include <utility>

#include "ballbar/workflow/error.hpp"

namespace ballbar::workflow {

PtyEmulator::PtyEmulator(device::EmulatorConfig config, device::Pacing pacing) : emu_(std::move(config)) {
    device::HostOptions ho;
    ho.pacing = pacing;
    ho.stop = &stop_;
    host_ = std::make_unique<device::EmulatorHost>(emu_, ho);
    thread_ = std::thread([this] {
        try {
            host_->run_pty([this](const std::string& path) {
                std::lock_guard lock(mutex_);
                path_ = path;
                cv_.notify_all();
            });
        } catch (const std::exception& e) {
            std::lock_guard lock(mutex_);
            error_ = e.what();
            cv_.notify_all();
        }
    });
}

PtyEmulator::~PtyEmulator() {
    halt();
}

void PtyEmulator::halt() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
}

std::string PtyEmulator::path() {
    std::unique_lock lock(mutex_);
    if (!cv_.wait_for(lock, std::chrono::seconds(10), [this] { return !path_.empty() || !error_.empty(); }))
        throw Error(ErrorCategory::device, "the emulator did not open a pseudo-terminal");
    if (!error_.empty()) throw Error(ErrorCategory::device, "emulator: " + error_);
    return path_;
}

}  // namespace ballbar::workflow
