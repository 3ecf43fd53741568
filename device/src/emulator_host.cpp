// SPDX-License-Identifier: MIT
#include "ballbar/device/emulator_host.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <thread>

namespace ballbar::device {

using namespace std::chrono;

namespace {
[[noreturn]] void sys_fail(const std::string& what) {
    throw DeviceError(DeviceErrorKind::Io, what + ": " + std::strerror(errno));
}
}  // namespace

// ---- PseudoTerminal ----

PseudoTerminal::PseudoTerminal() {
    master_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (master_ < 0) sys_fail("posix_openpt");
    if (::grantpt(master_) != 0 || ::unlockpt(master_) != 0) {
        ::close(master_);
        sys_fail("grantpt/unlockpt");
    }
    char name[128];
    if (::ptsname_r(master_, name, sizeof name) != 0) {
        ::close(master_);
        sys_fail("ptsname");
    }
    path_ = name;
    slave_ = ::open(name, O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (slave_ < 0) {
        ::close(master_);
        sys_fail("open " + path_);
    }
    termios t{};
    ::tcgetattr(slave_, &t);
    ::cfmakeraw(&t);
    ::tcsetattr(slave_, TCSANOW, &t);
    ::fcntl(master_, F_SETFL, ::fcntl(master_, F_GETFL) | O_NONBLOCK);
}

PseudoTerminal::~PseudoTerminal() {
    if (slave_ >= 0) ::close(slave_);
    if (master_ >= 0) ::close(master_);
}

// ---- TcpListener ----

TcpListener::TcpListener(std::uint16_t port) {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd_ < 0) sys_fail("socket");
    int one = 1;
    ::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(port);
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 || ::listen(fd_, 4) != 0) {
        const int err = errno;
        ::close(fd_);
        errno = err;
        sys_fail("cannot listen on 127.0.0.1:" + std::to_string(port));
    }
    socklen_t len = sizeof addr;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&addr), &len);
    port_ = ntohs(addr.sin_port);
}

TcpListener::~TcpListener() {
    ::close(fd_);
}

int TcpListener::accept(milliseconds timeout) {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(timeout.count())) <= 0) return -1;
    const int fd = ::accept4(fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd >= 0) {
        int one = 1;
        ::setsockopt(fd, IPPROTO_TCP, 1 /* TCP_NODELAY */, &one, sizeof one);
    }
    return fd;
}

// ---- EmulatorHost ----

EmulatorHost::EmulatorHost(Emulator& emulator, HostOptions options)
    : emu_(emulator),
      options_(std::move(options)),
      last_real_(steady_clock::now()),
      requests_seen_(emu_.counters().requests),
      last_request_real_(last_real_) {
    tx_.reserve(options_.backlog_bytes * 2);
    // As fast as the host reads, the emulator's clock runs many times faster than the wall clock; a
    // watchdog counted on it would stop the stream between two keep-alives of a live host.
    if (options_.pacing == Pacing::Simulated) emu_.set_external_watchdog(true);
}

void EmulatorHost::tick() {
    const auto now = steady_clock::now();
    const auto real_us = static_cast<std::uint64_t>(duration_cast<microseconds>(now - last_real_).count());
    last_real_ = now;
    emu_.advance_to(emu_.now_us() + real_us);
    if (options_.pacing == Pacing::Simulated) {
        if (emu_.counters().requests != requests_seen_) {
            requests_seen_ = emu_.counters().requests;
            last_request_real_ = now;
        }
        const double watchdog_s = emu_.config().instrument.watchdog_s;
        if (watchdog_s > 0 && emu_.streaming() && duration<double>(now - last_request_real_).count() > watchdog_s)
            emu_.watchdog_expired();
    }
    if (options_.pacing == Pacing::Simulated && emu_.streaming()) {
        for (int i = 0; i < 256 && emu_.pending_output() + (tx_.size() - tx_off_) < options_.backlog_bytes; ++i) {
            emu_.advance_to(emu_.now_us() + static_cast<std::uint64_t>(options_.step.count()));
            if (!emu_.connected()) break;
        }
    }
}

EmulatorHost::End EmulatorHost::serve_fd(int fd) {
    std::array<std::uint8_t, 4096> rx{};
    tx_.clear();
    tx_off_ = 0;
    while (true) {
        if (stopped()) return End::Stopped;
        tick();
        if (!emu_.connected()) return End::DeviceDisconnected;
        // Collect what the device has to say.
        if (tx_off_ == tx_.size()) {
            tx_.clear();
            tx_off_ = 0;
        }
        while (tx_.size() - tx_off_ < options_.backlog_bytes) {
            const std::size_t at = tx_.size();
            tx_.resize(at + 4096);
            const std::size_t n = emu_.take_device_bytes({tx_.data() + at, 4096});
            tx_.resize(at + n);
            if (n == 0) break;
        }
        const bool want_out = tx_off_ < tx_.size();
        pollfd p{fd, static_cast<short>(POLLIN | (want_out ? POLLOUT : 0)), 0};
        const bool hurry = options_.pacing == Pacing::Simulated && emu_.streaming();
        const int r = ::poll(&p, 1, hurry && want_out ? 100 : 1);
        if (r < 0 && errno != EINTR) sys_fail("poll");
        if (r <= 0) continue;
        if (p.revents & POLLIN) {
            const ssize_t n = ::read(fd, rx.data(), rx.size());
            if (n > 0) {
                emu_.on_host_bytes({rx.data(), static_cast<std::size_t>(n)});
            } else if (n == 0 || (errno != EAGAIN && errno != EINTR)) {
                return End::PeerClosed;
            }
        } else if (p.revents & (POLLHUP | POLLERR)) {
            return End::PeerClosed;
        }
        if ((p.revents & POLLOUT) && want_out) {
            const ssize_t n = ::write(fd, tx_.data() + tx_off_, tx_.size() - tx_off_);
            if (n > 0) {
                tx_off_ += static_cast<std::size_t>(n);
            } else if (n < 0 && errno != EAGAIN && errno != EINTR) {
                return End::PeerClosed;
            }
        }
    }
}

void EmulatorHost::wait_connected() {
    while (!emu_.connected() && !stopped()) {
        tick();
        // On simulated time nobody is served while the instrument is unplugged: its clock goes on ten
        // times faster than the wall clock (a simulated 8 s disconnect takes 0.8 s), as time goes faster
        // while it streams.
        if (options_.pacing == Pacing::Simulated) emu_.advance_to(emu_.now_us() + 10'000);
        std::this_thread::sleep_for(milliseconds(1));
    }
}

void EmulatorHost::run_pty(const std::function<void(const std::string&)>& on_pty, const std::string& link) {
    // The link is this host's only while it points where the host made it point: it is never made
    // over something that exists, and only ever replaced or removed while it still points to the
    // host's last pty (someone else's file or link at that path is left alone).
    std::string linked_to;  // the pty the host's link points to; empty: no link of the host's
    auto still_ours = [&] {
        std::error_code ec;
        return !linked_to.empty() && std::filesystem::is_symlink(link, ec) &&
               std::filesystem::read_symlink(link, ec).string() == linked_to && !ec;
    };
    auto drop_link = [&] {
        std::error_code ec;
        if (still_ours()) std::filesystem::remove(link, ec);
        linked_to.clear();
    };
    while (!stopped()) {
        End end;
        {
            PseudoTerminal pty;
            if (!link.empty()) {
                if (!linked_to.empty() && !still_ours())
                    event("the link " + link + " was changed by someone else: left as it is");
                drop_link();  // ours only; what else is there makes the new link fail, below
                std::error_code ec;
                std::filesystem::create_symlink(pty.path(), link, ec);
                if (ec)
                    event("cannot create symlink " + link + ": " + ec.message());
                else
                    linked_to = pty.path();
            }
            on_pty(pty.path());
            end = serve_fd(pty.master());
        }
        if (end == End::DeviceDisconnected) {
            event("simulated disconnect: pty closed");
            wait_connected();
        }
    }
    if (!link.empty()) drop_link();  // a link to a closed pty would mislead the next user of the path
}

void EmulatorHost::run_tcp(TcpListener& listener) {
    event("listening on tcp:127.0.0.1:" + std::to_string(listener.port()));
    std::array<std::uint8_t, 4096> sink{};
    while (!stopped()) {
        tick();
        const int fd = listener.accept(milliseconds(20));
        if (fd < 0) continue;
        if (!emu_.connected()) {
            ::close(fd);  // the instrument is "unplugged": refuse
            continue;
        }
        while (emu_.take_device_bytes(sink) > 0) {
        }  // a new connection starts a fresh stream
        event("client connected");
        const End end = serve_fd(fd);
        ::close(fd);
        if (end == End::PeerClosed) emu_.host_link_lost();
        event(end == End::DeviceDisconnected ? "simulated disconnect: connection closed" : "client left");
    }
}

}  // namespace ballbar::device
