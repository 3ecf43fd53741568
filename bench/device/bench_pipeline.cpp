// SPDX-License-Identifier: MIT
// Emulator → pseudo-terminal → serial link (termios) → driver → consumer, as fast as the consumer
// reads: samples/s with zero loss (target ≥ 1 M samples/s). The emulator runs at 5 kHz on simulated
// time in its own thread; the benchmark thread is the host.
#include <benchmark/benchmark.h>
#include <time.h>

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "ballbar/device/emulator_host.hpp"
#include "ballbar/device/instrument.hpp"
#include "ballbar/device/serial.hpp"

using namespace ballbar::device;

namespace {

double process_cpu_s() {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

void BM_EmulatorPtyDriver(benchmark::State& state) {
    EmulatorConfig cfg;
    cfg.instrument.sample_rate_hz = 5000;
    Emulator emu(cfg);
    std::atomic<bool> stop{false};
    std::mutex m;
    std::condition_variable cv;
    std::string path;
    std::thread host_thread([&] {
        HostOptions opt;
        opt.pacing = Pacing::Simulated;
        opt.stop = &stop;
        opt.step = std::chrono::microseconds(static_cast<long>(state.range(0)));
        EmulatorHost host(emu, opt);
        host.run_pty([&](const std::string& p) {
            std::lock_guard lock(m);
            path = p;
            cv.notify_all();
        });
    });
    {
        std::unique_lock lock(m);
        cv.wait(lock, [&] { return !path.empty(); });
    }
    std::int64_t samples = 0;
    std::uint64_t lost = 0;
    double seconds = 0;
    double cpu_seconds = 0;
    {
        Instrument inst(open_serial_transport(path));
        inst.identify();
        inst.start_streaming();
        std::vector<ballbar::analysis::BarSample> buf(16384);
        std::int64_t checksum = 0;
        for (auto _ : state) {
            const auto t0 = std::chrono::steady_clock::now();
            const double cpu0 = process_cpu_s();
            const auto end = t0 + std::chrono::milliseconds(1000);
            while (std::chrono::steady_clock::now() < end) {
                inst.poll(std::chrono::milliseconds(50));
                const std::size_t n = inst.read_samples(buf);
                for (std::size_t i = 0; i < n; ++i) checksum += buf[i].displacement_nm;  // the consumer
                samples += static_cast<std::int64_t>(n);
            }
            seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            cpu_seconds += process_cpu_s() - cpu0;
        }
        benchmark::DoNotOptimize(checksum);
        inst.stop_streaming();
        lost = inst.stats().lost_frames + inst.stats().queue_drops + inst.stats().invalid_frames;
    }
    stop = true;
    host_thread.join();
    state.counters["samples_per_s"] = static_cast<double>(samples) / seconds;
    // Both threads (emulator host and driver/consumer) together: what the pipeline costs when the
    // machine is shared and wall-clock rates say more about the load than about the code.
    state.counters["samples_per_cpu_s"] = static_cast<double>(samples) / cpu_seconds;
    state.counters["lost"] = static_cast<double>(lost);
    if (lost != 0) state.SkipWithError("samples were lost");
}
// Arg: the emulator's clock step per generation round, µs.
BENCHMARK(BM_EmulatorPtyDriver)->Arg(1000)->Arg(2000)->Iterations(3)->Unit(benchmark::kMillisecond);

}  // namespace

namespace {

/// The emulator alone: sample generation and framing at 5 kHz on simulated time.
void BM_EmulatorGenerate(benchmark::State& state) {
    EmulatorConfig cfg;
    cfg.instrument.sample_rate_hz = 5000;
    Emulator emu(cfg);
    ballbar::device::protocol::FrameBuffer start{};
    const auto n = ballbar::device::protocol::encode_empty(ballbar::device::protocol::MsgType::Start, 1, start);
    emu.on_host_bytes({start.data(), n});
    std::array<std::uint8_t, 65536> sink{};
    for (auto _ : state) {
        emu.advance_to(emu.now_us() + 100'000);  // 500 samples
        while (emu.take_device_bytes(sink) > 0) {
        }
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(emu.counters().samples));
}
BENCHMARK(BM_EmulatorGenerate);

}  // namespace
