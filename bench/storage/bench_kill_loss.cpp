// SPDX-License-Identifier: MIT
// How much of what the instrument measured a kill -9 loses. A child process (this program, re-run with
// --child) streams the device emulator on the steady clock (as a real instrument: 1 kHz, frames of 13)
// through the real driver into a SampleWriter; the parent kills it at a random moment and compares the
// device time the instrument had reached then with the last stored sample.
//   bench_storage_kill_loss [--runs N] [--batch-ms B] [--wall-ms W] [--dir DIR]
// --batch-ms / --wall-ms set SampleWriterOptions (defaults: the writer's own, 50 and 50; --wall-ms 0
// switches the wall-clock bound off, --batch-ms 100 --wall-ms 0 is the writer before the fix).
// Prints the loss per run and its median, 90th percentile and maximum. Creates and removes only its own
// database files in DIR (default: a new directory under /tmp).
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "ballbar/device/emulator.hpp"
#include "ballbar/device/instrument.hpp"
#include "ballbar/device/pipe.hpp"
#include "ballbar/storage/sample_writer.hpp"
#include "ballbar/storage/store.hpp"

namespace {

using namespace ballbar;
using namespace std::chrono;

void put(std::uint64_t v) {
    if (::write(STDOUT_FILENO, &v, sizeof v) != sizeof v) std::_Exit(4);
}

int child(const std::string& db, storage::SampleWriterOptions wo) {
    storage::Store store(db);
    storage::NewSession ns;
    ns.machine.type = analysis::MachineType::TTTRR;
    ns.machine.c_offset_mm = {0, 0, -100};
    ns.source = storage::SessionSource::emulator;
    ns.procedure = "kill-loss-bench";
    const auto id = store.create_session(ns);
    store.start_session(id);
    device::EmulatorConfig cfg;
    cfg.seed = 5;
    device::Emulator emu(cfg);
    const auto zero = steady_clock::now() - microseconds(emu.now_us());
    device::Instrument inst(std::make_unique<device::PipeTransport>(emu, device::Pacing::RealTime));
    inst.identify();
    inst.configure(1000, 1);
    storage::SampleWriter writer(store, id, wo);
    put(static_cast<std::uint64_t>(id));
    put(static_cast<std::uint64_t>(duration_cast<microseconds>(zero.time_since_epoch()).count()));
    inst.start_streaming();
    std::vector<analysis::BarSample> buf(512);
    while (true) {  // as the acquisition reads: poll, take what is queued, store it
        inst.poll(milliseconds(10));
        const std::size_t n = inst.read_samples(buf);
        for (std::size_t i = 0; i < n; ++i) writer.append(buf[i]);
    }
}

bool read_values(int fd, std::vector<std::uint64_t>& out, std::size_t want, milliseconds timeout) {
    std::string partial;
    const auto until = steady_clock::now() + timeout;
    while (out.size() < want && steady_clock::now() < until) {
        pollfd p{fd, POLLIN, 0};
        if (::poll(&p, 1, 50) <= 0) continue;
        char buf[64];
        const ssize_t n = ::read(fd, buf, sizeof buf);
        if (n <= 0) return false;
        partial.append(buf, static_cast<std::size_t>(n));
        while (partial.size() >= 8) {
            std::uint64_t v;
            std::memcpy(&v, partial.data(), 8);
            out.push_back(v);
            partial.erase(0, 8);
        }
    }
    return out.size() >= want;
}

}  // namespace

int main(int argc, char** argv) {
    int runs = 20;
    storage::SampleWriterOptions wo;
    std::string dir;
    std::string child_db;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool has = i + 1 < argc;
        if (a == "--runs" && has) {
            runs = std::stoi(argv[++i]);
        } else if (a == "--batch-ms" && has) {
            wo.max_batch_device_time_us = static_cast<std::uint64_t>(std::stod(argv[++i]) * 1000);
        } else if (a == "--wall-ms" && has) {
            const double w = std::stod(argv[++i]);
            wo.max_batch_wall_time =
                w > 0 ? milliseconds(static_cast<long>(w)) : duration_cast<milliseconds>(hours(24));
        } else if (a == "--dir" && has) {
            dir = argv[++i];
        } else if (a == "--child" && has) {
            child_db = argv[++i];
        } else {
            std::fprintf(stderr, "usage: %s [--runs N] [--batch-ms B] [--wall-ms W] [--dir DIR]\n", argv[0]);
            return 2;
        }
    }
    if (!child_db.empty()) return child(child_db, wo);

    const bool own_dir = dir.empty();
    if (own_dir) {
        char tmpl[] = "/tmp/ballbar-kill-loss-XXXXXX";
        if (!::mkdtemp(tmpl)) return 1;
        dir = tmpl;
    }
    const std::string db = dir + "/kill-loss.db";
    for (const char* suffix : {"", "-wal", "-shm", ".lock"}) {
        if (std::filesystem::exists(db + suffix)) {
            std::fprintf(stderr, "%s%s exists; not overwriting what this program did not create\n", db.c_str(), suffix);
            return 1;
        }
    }
    std::printf(
        "SampleWriter batch %.0f ms of device time, wall-clock bound %s; %d kills\n",
        static_cast<double>(wo.max_batch_device_time_us) * 1e-3,
        wo.max_batch_wall_time < hours(1) ? (std::to_string(wo.max_batch_wall_time.count()) + " ms").c_str() : "off",
        runs);
    std::mt19937 rng(20261201);
    std::uniform_int_distribution<int> delay(200, 1500);
    std::vector<double> losses;
    for (int r = 0; r < runs; ++r) {
        int fds[2];
        if (::pipe2(fds, O_CLOEXEC) != 0) return 1;
        const pid_t pid = ::fork();
        if (pid == 0) {
            ::dup2(fds[1], STDOUT_FILENO);
            std::vector<std::string> args = {
                "/proc/self/exe",
                "--child",
                db,
                "--batch-ms",
                std::to_string(static_cast<double>(wo.max_batch_device_time_us) * 1e-3),
                "--wall-ms",
                std::to_string(wo.max_batch_wall_time < hours(1) ? wo.max_batch_wall_time.count() : 0)};
            std::vector<char*> av;
            for (auto& s : args) av.push_back(s.data());
            av.push_back(nullptr);
            ::execv(av[0], av.data());
            std::_Exit(127);
        }
        ::close(fds[1]);
        std::vector<std::uint64_t> v;
        if (!read_values(fds[0], v, 2, seconds(10))) {
            std::fprintf(stderr, "child did not start\n");
            ::kill(pid, SIGKILL);
            ::waitpid(pid, nullptr, 0);
            return 1;
        }
        ::usleep(static_cast<useconds_t>(delay(rng)) * 1000);
        const auto kill_at = steady_clock::now();
        ::kill(pid, SIGKILL);
        ::waitpid(pid, nullptr, 0);
        ::close(fds[0]);
        const auto measured_us =
            duration_cast<microseconds>(kill_at.time_since_epoch()).count() - static_cast<std::int64_t>(v[1]);
        storage::Store store(db);
        const auto id = static_cast<std::int64_t>(v[0]);
        const auto n = store.next_seq(id);
        const double last_us = n > 0 ? static_cast<double>(store.samples(id, n - 1, 1).at(0).device_time_us) : 0.0;
        const double lost_ms = (static_cast<double>(measured_us) - last_us) * 1e-3;
        losses.push_back(lost_ms);
        std::printf("  run %2d: instrument at %8.1f ms, last stored %8.1f ms: lost %6.1f ms\n", r + 1,
                    static_cast<double>(measured_us) * 1e-3, last_us * 1e-3, lost_ms);
    }
    std::sort(losses.begin(), losses.end());
    const auto at = [&](double q) {
        return losses[std::min(losses.size() - 1, static_cast<std::size_t>(q * static_cast<double>(losses.size())))];
    };
    std::printf("lost per kill: median %.1f ms, 90th percentile %.1f ms, max %.1f ms (%zu kills)\n", at(0.5), at(0.9),
                losses.back(), losses.size());
    for (const char* suffix : {"", "-wal", "-shm", ".lock"}) std::filesystem::remove(db + suffix);
    if (own_dir) std::filesystem::remove(dir);
    return 0;
}
