// SPDX-License-Identifier: MIT
// Serial links: libserialport for real ports, termios for pseudo-terminals (docs/device.md).
#include "ballbar/device/serial.hpp"

#include <fcntl.h>
#include <libserialport.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "ballbar/device/usb.hpp"
#include "fd_link.hpp"

namespace ballbar::device {

namespace {

class FdTransport : public Transport {
  public:
    FdTransport(int fd, std::string path) : fd_(fd), uri_("serial:" + std::move(path)) {}
    void write(std::span<const std::uint8_t> data, std::chrono::milliseconds timeout) override {
        detail::fd_write(fd_, data, timeout, uri_);
    }
    std::size_t read(std::span<std::uint8_t> data, std::chrono::milliseconds timeout) override {
        return detail::fd_read(fd_, data, timeout, uri_);
    }
    std::string uri() const override { return uri_; }

  protected:
    int fd_;
    std::string uri_;
};

class SpTransport final : public FdTransport {
  public:
    SpTransport(sp_port* port, int fd, std::string path) : FdTransport(fd, std::move(path)), port_(port) {}
    ~SpTransport() override {
        sp_close(port_);
        sp_free_port(port_);
    }
    SpTransport(const SpTransport&) = delete;
    SpTransport& operator=(const SpTransport&) = delete;

  private:
    sp_port* port_;
};

class TermiosTransport final : public FdTransport {
  public:
    using FdTransport::FdTransport;
    ~TermiosTransport() override { ::close(fd_); }
    TermiosTransport(const TermiosTransport&) = delete;
    TermiosTransport& operator=(const TermiosTransport&) = delete;
};

[[noreturn]] void open_failed(const std::string& path, int err, const std::string& detail) {
    if (err == EACCES || err == EPERM) throw DeviceError(DeviceErrorKind::Permission, udev_permission_hint(path));
    if (err == ENOENT || err == ENODEV || err == ENXIO) {
        throw DeviceError(DeviceErrorKind::NotFound, "serial:" + path + ": no such port (" + std::strerror(err) + ")");
    }
    throw DeviceError(DeviceErrorKind::Io, "serial:" + path + ": cannot open: " + detail);
}

speed_t termios_speed(int baud) {
    switch (baud) {
        case 4800:
            return B4800;
        case 9600:
            return B9600;
        case 19200:
            return B19200;
        case 38400:
            return B38400;
        case 57600:
            return B57600;
        case 115200:
            return B115200;
        case 230400:
            return B230400;
        case 460800:
            return B460800;
        case 921600:
            return B921600;
        default:
            throw std::invalid_argument("unsupported baud rate " + std::to_string(baud));
    }
}

}  // namespace

bool is_pseudo_terminal(const std::string& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0 || !S_ISCHR(st.st_mode)) return false;
    const unsigned maj = major(st.st_rdev);
    return maj >= 136 && maj <= 143;
}

std::unique_ptr<Transport> open_libserialport_format(const std::string& path, const SerialFormat& f) {
    const int baud = f.baud;
    sp_port* port = nullptr;
    if (sp_get_port_by_name(path.c_str(), &port) != SP_OK) {
        const int err = sp_last_error_code();
        char* msg = sp_last_error_message();
        const std::string detail = msg ? msg : "unknown error";
        sp_free_error_message(msg);
        open_failed(path, err, detail);
    }
    if (sp_open(port, SP_MODE_READ_WRITE) != SP_OK) {
        const int err = sp_last_error_code();
        char* msg = sp_last_error_message();
        const std::string detail = msg ? msg : "unknown error";
        sp_free_error_message(msg);
        sp_free_port(port);
        open_failed(path, err, detail);
    }
    const bool ok = sp_set_baudrate(port, baud) == SP_OK && sp_set_bits(port, f.data_bits) == SP_OK &&
                    sp_set_parity(port, f.parity == 'E'   ? SP_PARITY_EVEN
                                        : f.parity == 'O' ? SP_PARITY_ODD
                                                          : SP_PARITY_NONE) == SP_OK &&
                    sp_set_stopbits(port, f.stop_bits) == SP_OK &&
                    sp_set_flowcontrol(port, SP_FLOWCONTROL_NONE) == SP_OK && sp_set_dtr(port, SP_DTR_ON) == SP_OK;
    int fd = -1;
    if (!ok || sp_get_port_handle(port, &fd) != SP_OK || fd < 0) {
        char* msg = sp_last_error_message();
        const std::string detail = msg ? msg : "unknown error";
        sp_free_error_message(msg);
        sp_close(port);
        sp_free_port(port);
        throw DeviceError(DeviceErrorKind::Io, "serial:" + path + ": cannot configure the port: " + detail);
    }
    sp_flush(port, SP_BUF_BOTH);
    return std::make_unique<SpTransport>(port, fd, path);
}

std::unique_ptr<Transport> open_termios_format(const std::string& path, const SerialFormat& f) {
    const int baud = f.baud;
    const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        const int err = errno;
        open_failed(path, err, std::strerror(err));
    }
    termios t{};
    if (::tcgetattr(fd, &t) != 0) {
        const int err = errno;
        ::close(fd);
        throw DeviceError(DeviceErrorKind::Io, "serial:" + path + ": not a terminal (" + std::strerror(err) + ")");
    }
    ::cfmakeraw(&t);
    t.c_cflag |= CLOCAL | CREAD;
    t.c_cflag &= ~static_cast<tcflag_t>(CRTSCTS | CSIZE | PARENB | PARODD | CSTOPB);
    t.c_cflag |= f.data_bits == 7 ? CS7 : CS8;
    if (f.parity != 'N') t.c_cflag |= PARENB | (f.parity == 'O' ? PARODD : 0);
    if (f.stop_bits == 2) t.c_cflag |= CSTOPB;
    ::cfsetispeed(&t, termios_speed(baud));
    ::cfsetospeed(&t, termios_speed(baud));
    int err = ::tcsetattr(fd, TCSANOW, &t) == 0 ? 0 : errno;
    if (err == EINVAL && (f.data_bits != 8 || f.parity != 'N') && is_pseudo_terminal(path)) {
        // A pseudo-terminal has no line format to carry: Linux's pty driver forces 8 data bits without
        // parity on every tcsetattr, and refuses (EINVAL) a request for 7 bits or parity once the pty
        // already holds that forced result — the second open of the same pty (a reconnect, the next
        // process: the Sylvac's 7E2). Ask again for what a pty keeps: the baud rate, the stop bits,
        // raw mode.
        t.c_cflag &= ~static_cast<tcflag_t>(CSIZE | PARENB | PARODD);
        t.c_cflag |= CS8;
        err = ::tcsetattr(fd, TCSANOW, &t) == 0 ? 0 : errno;
    }
    if (err != 0) {
        ::close(fd);
        throw DeviceError(DeviceErrorKind::Io, "serial:" + path + ": cannot configure: " + std::strerror(err));
    }
    ::tcflush(fd, TCIOFLUSH);
    return std::make_unique<TermiosTransport>(fd, path);
}

std::unique_ptr<Transport> open_libserialport_transport(const std::string& path, int baud) {
    return open_libserialport_format(path, SerialFormat{baud, 8, 'N', 1});
}

std::unique_ptr<Transport> open_termios_transport(const std::string& path, int baud) {
    return open_termios_format(path, SerialFormat{baud, 8, 'N', 1});
}

std::unique_ptr<Transport> open_serial_transport(const std::string& path, int baud) {
    return open_serial_transport(path, SerialFormat{baud, 8, 'N', 1});
}

std::unique_ptr<Transport> open_serial_transport(const std::string& path, const SerialFormat& format) {
    try {
        return open_libserialport_format(path, format);
    } catch (const DeviceError&) {
        // libserialport refuses bare pseudo-terminals (it looks the port up in sysfs, which has no entry
        // for a pty, and wants modem lines): use termios for those, and only for those.
        if (!is_pseudo_terminal(path)) throw;
    }
    return open_termios_format(path, format);
}

}  // namespace ballbar::device
