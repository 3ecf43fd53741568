// SPDX-License-Identifier: MIT
#include "ballbar/device/tcp.hpp"

#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "fd_link.hpp"

namespace ballbar::device {

namespace {

class TcpTransport final : public Transport {
  public:
    TcpTransport(int fd, std::string uri) : fd_(fd), uri_(std::move(uri)) {}
    ~TcpTransport() override { ::close(fd_); }
    TcpTransport(const TcpTransport&) = delete;
    TcpTransport& operator=(const TcpTransport&) = delete;
    void write(std::span<const std::uint8_t> data, std::chrono::milliseconds timeout) override {
        detail::fd_write(fd_, data, timeout, uri_);
    }
    std::size_t read(std::span<std::uint8_t> data, std::chrono::milliseconds timeout) override {
        return detail::fd_read(fd_, data, timeout, uri_);
    }
    std::string uri() const override { return uri_; }

  private:
    int fd_;
    std::string uri_;
};

}  // namespace

std::unique_ptr<Transport> open_tcp_transport(const std::string& host, std::uint16_t port,
                                              std::chrono::milliseconds timeout) {
    const std::string uri = "tcp:" + host + ":" + std::to_string(port);
    addrinfo hints{};
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    addrinfo* res = nullptr;
    if (const int rc = ::getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &res); rc != 0) {
        throw DeviceError(DeviceErrorKind::NotFound, uri + ": cannot resolve " + host + ": " + ::gai_strerror(rc));
    }
    std::string last = "no address";
    DeviceErrorKind kind = DeviceErrorKind::NotFound;
    for (addrinfo* a = res; a; a = a->ai_next) {
        const int fd = ::socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, a->ai_protocol);
        if (fd < 0) continue;
        int rc = ::connect(fd, a->ai_addr, a->ai_addrlen);
        if (rc != 0 && errno == EINPROGRESS) {
            pollfd p{fd, POLLOUT, 0};
            rc = ::poll(&p, 1, static_cast<int>(timeout.count()));
            if (rc == 0) {
                ::close(fd);
                last = "connection timed out";
                kind = DeviceErrorKind::Timeout;
                continue;
            }
            int err = 0;
            socklen_t len = sizeof err;
            ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len);
            rc = err == 0 ? 0 : -1;
            errno = err;
        }
        if (rc != 0) {
            last = std::strerror(errno);
            kind = errno == ECONNREFUSED ? DeviceErrorKind::NotFound : DeviceErrorKind::Io;
            ::close(fd);
            continue;
        }
        int one = 1;
        ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        ::freeaddrinfo(res);
        return std::make_unique<TcpTransport>(fd, uri);
    }
    ::freeaddrinfo(res);
    throw DeviceError(kind, uri + ": cannot connect: " + last);
}

}  // namespace ballbar::device
