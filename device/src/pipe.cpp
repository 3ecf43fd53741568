// SPDX-License-Identifier: MIT
#include "ballbar/device/pipe.hpp"

#include <algorithm>
#include <thread>

namespace ballbar::device {

PipeTransport::PipeTransport(Emulator& emulator, Pacing pacing, std::string uri)
    : emulator_(&emulator),
      pacing_(pacing),
      uri_(std::move(uri)),
      start_(std::chrono::steady_clock::now()),
      start_us_(emulator.now_us()) {}

PipeTransport::PipeTransport(std::unique_ptr<Emulator> emulator, Pacing pacing, std::string uri)
    : PipeTransport(*emulator, pacing, std::move(uri)) {
    owned_ = std::move(emulator);
}

void PipeTransport::check_connected() const {
    if (!emulator_->connected()) {
        throw DeviceError(DeviceErrorKind::Disconnected, uri_ + ": the emulated instrument went away");
    }
}

void PipeTransport::write(std::span<const std::uint8_t> data, std::chrono::milliseconds) {
    check_connected();
    emulator_->on_host_bytes(data);
}

std::size_t PipeTransport::read(std::span<std::uint8_t> data, std::chrono::milliseconds timeout) {
    using namespace std::chrono;
    if (pacing_ == Pacing::Simulated) {
        const auto end_us =
            emulator_->now_us() + static_cast<std::uint64_t>(duration_cast<microseconds>(timeout).count());
        while (true) {
            check_connected();
            if (const auto n = emulator_->take_device_bytes(data); n > 0) return n;
            if (emulator_->now_us() >= end_us) return 0;
            emulator_->advance_to(std::min(end_us, emulator_->now_us() + 1000));
        }
    }
    const auto deadline = steady_clock::now() + timeout;
    while (true) {
        const auto elapsed = duration_cast<microseconds>(steady_clock::now() - start_).count();
        emulator_->advance_to(start_us_ + static_cast<std::uint64_t>(elapsed));
        check_connected();
        if (const auto n = emulator_->take_device_bytes(data); n > 0) return n;
        const auto now = steady_clock::now();
        if (now >= deadline) return 0;
        std::this_thread::sleep_for(std::min<steady_clock::duration>(milliseconds(1), deadline - now));
    }
}

}  // namespace ballbar::device
