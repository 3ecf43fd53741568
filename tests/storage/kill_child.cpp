// SPDX-License-Identifier: MIT
// Helper of the kill test: streams samples into a session until it is killed.
//   storage_kill_child DB emulator|realtime|synthetic [RESUME_SESSION_ID]
// Writes to stdout (a pipe), as native 8-byte integers: first the session id, then after every
// SampleWriter::append the number of samples appended so far by this process. `realtime`: the emulator
// runs on the steady clock (as a real instrument does) and, after the session id, the child writes the
// CLOCK_MONOTONIC time in µs at which the device clock read 0, so the parent knows how much the
// instrument had measured when it killed the child.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <numbers>
#include <string>

#include "ballbar/storage/sample_writer.hpp"
#include "ballbar/storage/store.hpp"

#ifdef BALLBAR_HAVE_EMULATOR
#include <chrono>
#include <memory>
#include <span>
#include <vector>

#include "ballbar/device/emulator.hpp"
#include "ballbar/device/instrument.hpp"
#include "ballbar/device/pipe.hpp"
#endif

namespace {

using namespace ballbar;

void report(std::uint64_t value) {
    const char* p = reinterpret_cast<const char*>(&value);
    std::size_t left = sizeof value;
    while (left > 0) {
        const ssize_t n = ::write(STDOUT_FILENO, p, left);
        if (n <= 0) std::_Exit(4);
        p += n;
        left -= static_cast<std::size_t>(n);
    }
}

/// A deterministic bar signal at 1 kHz: a slow 5 µm sine, a little structured "noise", drifting temperature.
analysis::BarSample synthetic(std::uint64_t i) {
    analysis::BarSample s;
    s.device_time_us = 1'000 + i * 1000;
    const double t = static_cast<double>(i) * 1e-3;
    s.displacement_nm = static_cast<std::int32_t>(
        std::lround(5000 * std::sin(2 * std::numbers::pi * t / 2.0) + 37 * std::sin(static_cast<double>(i) * 1.7)));
    s.flags = 0;
    s.bar_temp_C = static_cast<float>(20.3 + t * 1e-3);
    return s;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: storage_kill_child DB emulator|synthetic [RESUME_ID]\n");
        return 2;
    }
    try {
        storage::Store store(argv[1]);
        std::int64_t id = 0;
        if (argc > 3) {
            id = std::stoll(argv[3]);
            store.resume_session(id);
        } else {
            storage::NewSession ns;
            ns.machine.type = analysis::MachineType::TTTRR;
            ns.machine.c_offset_mm = {0, 0, -100};
            ns.source = std::strcmp(argv[2], "emulator") == 0 ? storage::SessionSource::emulator
                                                              : storage::SessionSource::device;
            ns.procedure = "kill-test";
            id = store.create_session(ns);
            store.start_session(id);
        }
        report(static_cast<std::uint64_t>(id));
        storage::SampleWriter writer(store, id);
        std::uint64_t appended = 0;
        const bool realtime = std::strcmp(argv[2], "realtime") == 0;
        if (std::strcmp(argv[2], "emulator") == 0 || realtime) {
#ifdef BALLBAR_HAVE_EMULATOR
            using namespace std::chrono_literals;
            device::EmulatorConfig cfg;
            cfg.seed = 11;
            device::Emulator emu(cfg);
            const auto zero = std::chrono::steady_clock::now() - std::chrono::microseconds(emu.now_us());
            device::Instrument inst(std::make_unique<device::PipeTransport>(
                emu, realtime ? device::Pacing::RealTime : device::Pacing::Simulated));
            if (realtime) {
                report(static_cast<std::uint64_t>(
                    std::chrono::duration_cast<std::chrono::microseconds>(zero.time_since_epoch()).count()));
            }
            inst.identify();
            inst.configure(1000, 1);
            inst.start_streaming();
            std::vector<analysis::BarSample> buf(512);
            while (true) {
                inst.poll(10ms);
                const std::size_t n = inst.read_samples(std::span(buf));
                for (std::size_t i = 0; i < n; ++i) {
                    writer.append(buf[i]);
                    report(++appended);
                }
            }
#else
            std::fprintf(stderr, "built without the device emulator\n");
            return 2;
#endif
        }
        while (true) {
            writer.append(synthetic(appended));
            report(++appended);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "storage_kill_child: %s\n", e.what());
        return 1;
    }
}
