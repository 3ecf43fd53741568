// SPDX-License-Identifier: MIT
// Links to the gauge emulator: the USB-ITN in process, the serial gauges behind a pseudo-terminal.
#include <poll.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <thread>

#include "ballbar/device/emulator_host.hpp"
#include "ballbar/device/gauge_emulator.hpp"

namespace ballbar::device::gauge {
namespace {

class EmulatedItnLink final : public ItnLink {
  public:
    EmulatedItnLink(GaugeEmulator& emu, std::string serial) : emu_(emu), serial_(std::move(serial)) {}
    void control_out(std::uint8_t request, std::uint16_t value, std::span<const std::uint8_t> data,
                     std::chrono::milliseconds) override {
        emu_.control_out(request, value, data);
    }
    std::size_t control_in(std::uint8_t request, std::uint16_t value, std::span<std::uint8_t> data,
                           std::chrono::milliseconds) override {
        const int n = emu_.control_in(request, value, data);
        if (n < 0) throw DeviceError(DeviceErrorKind::Io, uri() + ": control IN stalled");
        return static_cast<std::size_t>(n);
    }
    std::size_t interrupt_in(std::span<std::uint8_t> data, std::chrono::milliseconds timeout) override {
        const auto deadline = std::chrono::steady_clock::now() + timeout;
        for (;;) {
            if (const std::size_t n = emu_.take_interrupt(data); n > 0) return n;
            if (std::chrono::steady_clock::now() >= deadline) return 0;
            std::this_thread::sleep_for(std::chrono::microseconds(200));
        }
    }
    std::string serial() const override { return serial_; }
    std::string product() const override { return "USB-ITN (emulated)"; }
    std::string uri() const override { return "mitutoyo-itn:" + serial_; }

  private:
    GaugeEmulator& emu_;
    std::string serial_;
};

}  // namespace

std::unique_ptr<ItnLink> make_emulated_itn_link(GaugeEmulator& emulator, std::string serial) {
    return std::make_unique<EmulatedItnLink>(emulator, std::move(serial));
}

struct GaugePtyHost::Impl {
    GaugeEmulator& emu;
    PseudoTerminal pty;
    std::atomic<bool> stop{false};
    std::thread thread;

    explicit Impl(GaugeEmulator& e) : emu(e) {
        thread = std::thread([this] { serve(); });
    }
    void serve() {
        std::array<std::uint8_t, 512> buf{};
        std::vector<std::uint8_t> tx;
        while (!stop) {
            pollfd p{pty.master(), POLLIN, 0};
            if (::poll(&p, 1, 1) > 0 && (p.revents & POLLIN)) {
                const ssize_t n = ::read(pty.master(), buf.data(), buf.size());
                if (n > 0) emu.on_host_bytes({buf.data(), static_cast<std::size_t>(n)});
            }
            std::size_t n;
            while ((n = emu.take_device_bytes(buf)) > 0) tx.insert(tx.end(), buf.begin(), buf.begin() + n);
            while (!tx.empty() && !stop) {
                const ssize_t w = ::write(pty.master(), tx.data(), tx.size());
                if (w > 0) {
                    tx.erase(tx.begin(), tx.begin() + w);
                } else if (w < 0 && errno != EAGAIN && errno != EINTR) {
                    tx.clear();  // nobody reads: the reply is lost, as on a line without a host
                } else {
                    std::this_thread::sleep_for(std::chrono::microseconds(200));
                }
            }
        }
    }
    ~Impl() {
        stop = true;
        thread.join();
    }
};

GaugePtyHost::GaugePtyHost(GaugeEmulator& emulator) : impl_(std::make_unique<Impl>(emulator)) {}
GaugePtyHost::~GaugePtyHost() = default;
const std::string& GaugePtyHost::path() const {
    return impl_->pty.path();
}

}  // namespace ballbar::device::gauge
