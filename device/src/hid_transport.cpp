// SPDX-License-Identifier: MIT
// HID link over hidapi (hidraw backend): the byte stream chunked into 64-byte reports.
#include <fcntl.h>
#include <hidapi/hidapi.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <climits>
#include <cstring>

#include "ballbar/device/hid.hpp"
#include "ballbar/device/ids.hpp"
#include "ballbar/device/usb.hpp"
#include "wide_text.hpp"

namespace ballbar::device {

std::vector<std::array<std::uint8_t, kHidReportSize>> hid_pack_reports(std::span<const std::uint8_t> data) {
    std::vector<std::array<std::uint8_t, kHidReportSize>> reports;
    reports.reserve((data.size() + kHidPayloadMax - 1) / kHidPayloadMax);
    for (std::size_t pos = 0; pos < data.size(); pos += kHidPayloadMax) {
        const std::size_t n = std::min(kHidPayloadMax, data.size() - pos);
        std::array<std::uint8_t, kHidReportSize> r{};
        r[0] = static_cast<std::uint8_t>(n);
        std::memcpy(r.data() + 1, data.data() + pos, n);
        reports.push_back(r);
    }
    return reports;
}

std::span<const std::uint8_t> hid_report_payload(std::span<const std::uint8_t, kHidReportSize> report) {
    if (report[0] > kHidPayloadMax) {
        throw DeviceError(DeviceErrorKind::Protocol, "HID report announces " + std::to_string(report[0]) +
                                                         " payload bytes, at most " + std::to_string(kHidPayloadMax) +
                                                         " fit");
    }
    return report.subspan(1, report[0]);
}

namespace {

std::string hid_text(hid_device* dev) {
    return detail::narrow(hid_error(dev));
}

int to_hid_timeout(std::chrono::milliseconds timeout) {
    return static_cast<int>(std::clamp<std::chrono::milliseconds::rep>(timeout.count(), 0, INT_MAX));
}

bool node_exists(const std::string& path) {
    struct stat st {};
    return ::stat(path.c_str(), &st) == 0;
}

class HidTransport final : public Transport {
  public:
    HidTransport(hid_device* dev, std::string path, std::string uri)
        : dev_(dev), path_(std::move(path)), uri_(std::move(uri)) {}
    ~HidTransport() override { hid_close(dev_); }
    HidTransport(const HidTransport&) = delete;
    HidTransport& operator=(const HidTransport&) = delete;

    /// hidraw writes block until the device takes the report; the timeout is not enforceable there.
    void write(std::span<const std::uint8_t> data, std::chrono::milliseconds /*timeout*/) override {
        check_present();
        for (const auto& r : hid_pack_reports(data)) {
            std::array<std::uint8_t, kHidReportSize + 1> buf{};  // byte 0: report ID 0 (unnumbered reports)
            std::memcpy(buf.data() + 1, r.data(), r.size());
            errno = 0;
            const int n = hid_write(dev_, buf.data(), buf.size());
            const int err = errno;
            if (n < 0) {
                if (err == ENODEV || err == ESHUTDOWN || err == ENXIO || err == EIO || !node_exists(path_)) {
                    disconnected("write: " + hid_text(dev_));
                }
                throw DeviceError(DeviceErrorKind::Io, uri_ + ": HID write failed: " + hid_text(dev_));
            }
        }
    }

    std::size_t read(std::span<std::uint8_t> data, std::chrono::milliseconds timeout) override {
        if (data.empty()) return 0;
        if (pos_ == pending_.size()) {
            check_present();
            pending_.clear();
            pos_ = 0;
            const auto deadline = std::chrono::steady_clock::now() + timeout;
            while (pending_.empty()) {
                const auto left =
                    std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
                std::array<std::uint8_t, kHidReportSize> r{};
                const int n = hid_read_timeout(dev_, r.data(), r.size(), to_hid_timeout(std::max(left, {})));
                // hidraw reports a vanished device as a poll error (POLLHUP) or a failed read.
                if (n < 0) disconnected("read: " + hid_text(dev_));
                if (n == 0) {
                    if (!node_exists(path_)) disconnected("the device node is gone");
                    return 0;
                }
                if (static_cast<std::size_t>(n) != kHidReportSize) {
                    throw DeviceError(DeviceErrorKind::Protocol, uri_ + ": HID input report of " + std::to_string(n) +
                                                                     " bytes, expected " +
                                                                     std::to_string(kHidReportSize));
                }
                const auto payload = hid_report_payload(std::span<const std::uint8_t, kHidReportSize>(r));
                pending_.assign(payload.begin(), payload.end());  // an empty report carries nothing: read on
                if (pending_.empty() && std::chrono::steady_clock::now() >= deadline) return 0;
            }
        }
        const std::size_t n = std::min(data.size(), pending_.size() - pos_);
        std::memcpy(data.data(), pending_.data() + pos_, n);
        pos_ += n;
        return n;
    }

    std::string uri() const override { return uri_; }

  private:
    void check_present() const {
        if (gone_) throw DeviceError(DeviceErrorKind::Disconnected, uri_ + ": the HID device was disconnected");
    }
    [[noreturn]] void disconnected(const std::string& why) {
        gone_ = true;
        throw DeviceError(DeviceErrorKind::Disconnected, uri_ + ": the HID device was disconnected (" + why + ")");
    }

    hid_device* dev_;
    std::string path_;
    std::string uri_;
    std::vector<std::uint8_t> pending_;
    std::size_t pos_ = 0;
    std::atomic<bool> gone_{false};  // set by the reader or the writer thread
};

}  // namespace

std::unique_ptr<Transport> open_hid_transport(std::uint16_t vid, std::uint16_t pid, const std::string& serial) {
    const std::string name = hex4(vid) + ":" + hex4(pid) + (serial.empty() ? "" : " with serial " + serial);
    if (hid_init() != 0) throw DeviceError(DeviceErrorKind::Io, "cannot initialise hidapi: " + hid_text(nullptr));
    std::string path;
    std::string dev_serial;
    hid_device_info* list = hid_enumerate(vid, pid);
    for (hid_device_info* i = list; i; i = i->next) {
        const std::string s = detail::narrow(i->serial_number);
        if (!serial.empty() && s != serial) continue;
        path = i->path ? i->path : "";
        dev_serial = s;
        break;
    }
    hid_free_enumeration(list);
    if (path.empty()) throw DeviceError(DeviceErrorKind::NotFound, "no HID device " + name + " found");

    // Classify an open failure ourselves: hidapi keeps only a message, not errno.
    const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
    if (fd < 0) {
        const int err = errno;
        if (err == EACCES || err == EPERM) throw DeviceError(DeviceErrorKind::Permission, udev_permission_hint(path));
        if (err == ENOENT || err == ENODEV || err == ENXIO) {
            throw DeviceError(DeviceErrorKind::NotFound, path + ": the HID device vanished while opening");
        }
        throw DeviceError(DeviceErrorKind::Io, "cannot open " + path + ": " + std::strerror(err));
    }
    ::close(fd);
    hid_device* dev = hid_open_path(path.c_str());
    if (!dev) throw DeviceError(DeviceErrorKind::Io, "cannot open HID device " + path + ": " + hid_text(nullptr));
    std::string uri = "hid:" + hex4(vid) + ":" + hex4(pid) + (dev_serial.empty() ? "" : ":" + dev_serial);
    return std::make_unique<HidTransport>(dev, std::move(path), std::move(uri));
}

}  // namespace ballbar::device
