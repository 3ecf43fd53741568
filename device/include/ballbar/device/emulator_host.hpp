// SPDX-License-Identifier: MIT
// Hosting the emulator behind a real link: a pseudo-terminal (`ballbar emulate --pty`, the host
// connects with serial:/dev/pts/N) or a loopback TCP port (`ballbar emulate --tcp PORT`). The host
// shuttles bytes between the link and the Emulator and drives its clock: in real time, or as fast as
// the consumer reads while streaming (benchmarks, CI).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "ballbar/device/emulator.hpp"
#include "ballbar/device/pipe.hpp"

namespace ballbar::device {

struct HostOptions {
    Pacing pacing = Pacing::RealTime;                  ///< Simulated here means: as fast as possible while streaming
    const std::atomic<bool>* stop = nullptr;           ///< serving ends when it becomes true
    std::size_t backlog_bytes = 32 * 1024;             ///< as-fast-as-possible: stay this far ahead
    std::chrono::microseconds step{2000};              ///< as-fast-as-possible: clock step
    std::function<void(const std::string&)> on_event;  ///< "listening on ...", "client connected", ...
};

/// A pseudo-terminal pair. The host keeps a slave descriptor open itself, so clients may come and go
/// without the master seeing a hang-up; destroying it hangs up the clients (a pulled cable).
class PseudoTerminal {
  public:
    PseudoTerminal();
    ~PseudoTerminal();
    PseudoTerminal(const PseudoTerminal&) = delete;
    PseudoTerminal& operator=(const PseudoTerminal&) = delete;
    int master() const { return master_; }
    const std::string& path() const { return path_; }

  private:
    int master_ = -1;
    int slave_ = -1;
    std::string path_;
};

/// Loopback TCP listener (127.0.0.1 only). Port 0 picks a free port.
class TcpListener {
  public:
    explicit TcpListener(std::uint16_t port);
    ~TcpListener();
    TcpListener(const TcpListener&) = delete;
    TcpListener& operator=(const TcpListener&) = delete;
    std::uint16_t port() const { return port_; }
    /// A connected socket, or -1 when nobody connected within `timeout`.
    int accept(std::chrono::milliseconds timeout);

  private:
    int fd_ = -1;
    std::uint16_t port_ = 0;
};

class EmulatorHost {
  public:
    EmulatorHost(Emulator& emulator, HostOptions options);

    enum class End { Stopped, PeerClosed, DeviceDisconnected };
    /// Serves one byte-stream descriptor until stop, the peer closes it, or the emulator simulates a
    /// disconnect.
    End serve_fd(int fd);
    /// Moves the emulator's clock on by the pacing rule (call while no link is up).
    void tick();

    /// Serves on pseudo-terminals until stop; calls `on_pty(path)` for each (a new one after each
    /// simulated disconnect). If `link` is not empty it is kept as a symlink to the current pty.
    void run_pty(const std::function<void(const std::string&)>& on_pty, const std::string& link = {});
    /// Serves TCP clients one at a time until stop.
    void run_tcp(TcpListener& listener);

    bool stopped() const { return options_.stop && options_.stop->load(); }

  private:
    void event(const std::string& what) const {
        if (options_.on_event) options_.on_event(what);
    }
    void wait_connected();

    Emulator& emu_;
    HostOptions options_;
    std::chrono::steady_clock::time_point last_real_;
    // Pacing::Simulated: the instrument's watchdog counts the host's silence on the wall clock.
    std::uint64_t requests_seen_ = 0;
    std::chrono::steady_clock::time_point last_request_real_;
    std::vector<std::uint8_t> tx_;
    std::size_t tx_off_ = 0;
};

}  // namespace ballbar::device
