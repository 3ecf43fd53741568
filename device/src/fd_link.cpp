// SPDX-License-Identifier: MIT
#include "fd_link.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "ballbar/device/transport.hpp"

namespace ballbar::device::detail {

using namespace std::chrono;

namespace {

bool is_gone(int err) {
    return err == EIO || err == ENXIO || err == ENODEV || err == ECONNRESET || err == EPIPE || err == ENOTCONN;
}

[[noreturn]] void fail(int err, const std::string& what, const char* op) {
    if (is_gone(err))
        throw DeviceError(DeviceErrorKind::Disconnected, what + ": the link went away (" + std::strerror(err) + ")");
    throw DeviceError(DeviceErrorKind::Io, what + ": " + op + " failed: " + std::strerror(err));
}

int poll_ms(steady_clock::time_point deadline) {
    const auto left = duration_cast<milliseconds>(deadline - steady_clock::now()).count();
    return static_cast<int>(std::max<long long>(0, std::min<long long>(left, 1000 * 60)));
}

}  // namespace

std::size_t fd_read(int fd, std::span<std::uint8_t> data, milliseconds timeout, const std::string& what) {
    const auto deadline = steady_clock::now() + timeout;
    while (true) {
        pollfd p{fd, POLLIN, 0};
        const int r = ::poll(&p, 1, poll_ms(deadline));
        if (r < 0) {
            if (errno == EINTR) continue;
            fail(errno, what, "poll");
        }
        if (r == 0) return 0;
        if (p.revents & (POLLIN | POLLHUP | POLLERR)) {
            const ssize_t n = ::read(fd, data.data(), data.size());
            if (n > 0) return static_cast<std::size_t>(n);
            if (n == 0) throw DeviceError(DeviceErrorKind::Disconnected, what + ": the link went away (end of file)");
            if (errno == EAGAIN || errno == EINTR) {
                if (steady_clock::now() >= deadline) return 0;
                continue;
            }
            fail(errno, what, "read");
        }
        if (p.revents & POLLNVAL) throw DeviceError(DeviceErrorKind::Io, what + ": the port is closed");
    }
}

void fd_write(int fd, std::span<const std::uint8_t> data, milliseconds timeout, const std::string& what) {
    const auto deadline = steady_clock::now() + timeout;
    while (!data.empty()) {
        const ssize_t n = ::send(fd, data.data(), data.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
        ssize_t w = n;
        if (n < 0 && errno == ENOTSOCK) w = ::write(fd, data.data(), data.size());
        if (w > 0) {
            data = data.subspan(static_cast<std::size_t>(w));
            continue;
        }
        if (w < 0 && errno != EAGAIN && errno != EINTR) fail(errno, what, "write");
        pollfd p{fd, POLLOUT, 0};
        const int r = ::poll(&p, 1, poll_ms(deadline));
        if (r < 0 && errno != EINTR) fail(errno, what, "poll");
        if (r == 0) throw DeviceError(DeviceErrorKind::Timeout, what + ": write timed out");
        if (p.revents & (POLLHUP | POLLERR)) {
            throw DeviceError(DeviceErrorKind::Disconnected, what + ": the link went away");
        }
    }
}

}  // namespace ballbar::device::detail
