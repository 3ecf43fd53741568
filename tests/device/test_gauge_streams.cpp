// SPDX-License-Identifier: MIT
// Each gauge driver against byte streams written by hand from the protocol grammars
// (tests/data/gauges/*.stream): the serial drivers through a pseudo-terminal (the real serial transport,
// libmodbus for Modbus), the USB-ITN driver over a scripted USB link. A stream that the driver does not
// send byte for byte, or an answer it misreads, fails the test.
#include <gtest/gtest.h>
#include <poll.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <deque>
#include <mutex>
#include <thread>

#include "ballbar/device/emulator_host.hpp"
#include "ballbar/device/gauge.hpp"
#include "gauge_stream.hpp"

namespace ballbar::device::gauge {
namespace {

using namespace std::chrono_literals;
using testing::Exchange;
using testing::Step;

std::vector<Exchange> all_exchanges(const std::vector<Step>& steps) {
    std::vector<Exchange> v;
    for (const auto& s : steps) v.insert(v.end(), s.exchanges.begin(), s.exchanges.end());
    return v;
}

std::string printable(const std::string& s) {
    std::string o;
    for (unsigned char c : s) {
        if (c >= 0x20 && c < 0x7f) {
            o.push_back(static_cast<char>(c));
        } else {
            char b[8];
            std::snprintf(b, sizeof b, "\\x%02X", c);
            o += b;
        }
    }
    return o;
}

/// The device side of a stream behind a pty: waits for each expected host message, answers it.
class Replay {
  public:
    explicit Replay(std::vector<Exchange> ex) : ex_(std::move(ex)) {
        thread_ = std::thread([this] { run(); });
    }
    ~Replay() {
        stop_ = true;
        thread_.join();
    }
    const std::string& path() const { return pty_.path(); }
    std::string error() {
        std::lock_guard lock(m_);
        return error_;
    }
    std::size_t answered() const { return next_; }

  private:
    void run() {
        std::string rx;
        char buf[256];
        while (!stop_) {
            pollfd p{pty_.master(), POLLIN, 0};
            if (::poll(&p, 1, 2) <= 0) continue;
            const ssize_t n = ::read(pty_.master(), buf, sizeof buf);
            if (n <= 0) continue;
            rx.append(buf, static_cast<std::size_t>(n));
            while (next_ < ex_.size() && rx.size() >= ex_[next_].host.size()) {
                const Exchange& e = ex_[next_];
                if (rx.compare(0, e.host.size(), e.host) != 0) {
                    std::lock_guard lock(m_);
                    error_ = "exchange " + std::to_string(next_ + 1) + ": the host sent '" + printable(rx) +
                             "', the stream expects '" + printable(e.host) + "'";
                    rx.clear();
                    break;
                }
                rx.erase(0, e.host.size());
                if (!e.device.empty()) (void)!::write(pty_.master(), e.device.data(), e.device.size());
                ++next_;
            }
            if (next_ >= ex_.size() && !rx.empty()) {
                std::lock_guard lock(m_);
                error_ = "the host sent '" + printable(rx) + "' after the end of the stream";
                rx.clear();
            }
        }
    }
    std::vector<Exchange> ex_;
    PseudoTerminal pty_;
    std::atomic<bool> stop_{false};
    std::atomic<std::size_t> next_{0};
    std::mutex m_;
    std::string error_;
    std::thread thread_;
};

/// The USB-ITN side of a stream: init transfers checked, commands matched, replies on interrupt IN.
class ScriptedItn final : public ItnLink {
  public:
    explicit ScriptedItn(std::vector<Exchange> ex) : ex_(std::move(ex)) {}
    void control_out(std::uint8_t request, std::uint16_t value, std::span<const std::uint8_t> data,
                     std::chrono::milliseconds) override {
        if (request == kItnRequestInit) {
            EXPECT_EQ(value, kItnInitValue);
            initialised_ = true;
            return;
        }
        ASSERT_EQ(request, kItnRequestCommand);
        ASSERT_TRUE(initialised_) << "command before the init request";
        ASSERT_LT(next_, ex_.size()) << "command after the end of the stream";
        const std::string got(data.begin(), data.end());
        EXPECT_EQ(printable(got), printable(ex_[next_].host)) << "exchange " << next_ + 1;
        pending_.insert(pending_.end(), ex_[next_].device.begin(), ex_[next_].device.end());
        ++next_;
    }
    std::size_t control_in(std::uint8_t request, std::uint16_t, std::span<std::uint8_t> data,
                           std::chrono::milliseconds) override {
        EXPECT_EQ(request, kItnRequestStatus);
        EXPECT_TRUE(initialised_);
        data[0] = 0;
        return 1;
    }
    std::size_t interrupt_in(std::span<std::uint8_t> data, std::chrono::milliseconds timeout) override {
        if (pending_.empty()) {
            std::this_thread::sleep_for(std::min(timeout, 5ms));
            return 0;
        }
        const std::size_t n = std::min({data.size(), pending_.size(), std::size_t{8}});  // 8-byte reports
        std::copy_n(pending_.begin(), n, data.begin());
        pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(n));
        return n;
    }
    std::string serial() const override { return "ITN0042"; }
    std::string product() const override { return "USB-ITN-B"; }
    std::string uri() const override { return "mitutoyo-itn:ITN0042"; }
    std::size_t answered() const { return next_; }

  private:
    std::vector<Exchange> ex_;
    std::size_t next_ = 0;
    bool initialised_ = false;
    std::deque<std::uint8_t> pending_;
};

bool has(const std::vector<std::string>& v, const char* w) {
    return std::find(v.begin(), v.end(), w) != v.end();
}

void run_steps(Gauge& g, const std::vector<Step>& steps, const std::string& name) {
    for (const Step& s : steps) {
        SCOPED_TRACE(name + ":" + std::to_string(s.line));
        if (s.action == "identify") {
            const Identity id = g.identify();
            EXPECT_EQ(id.inch, has(s.expect, "inch"));
            EXPECT_EQ(id.low_battery, has(s.expect, "low-battery"));
            continue;
        }
        ASSERT_EQ(s.action, "read");
        ASSERT_FALSE(s.expect.empty());
        const std::string& want = s.expect[0];
        try {
            const Reading r = g.read(150ms);
            if (want == "ok") {
                ASSERT_EQ(r.status, ReadingStatus::Ok);
                ASSERT_EQ(s.expect.size(), 2u);
                EXPECT_NEAR(r.value_mm(), std::stod(s.expect[1]), 1e-9);
            } else if (want == "not-ready") {
                EXPECT_EQ(r.status, ReadingStatus::NotReady);
            } else if (want == "out-of-range") {
                EXPECT_EQ(r.status, ReadingStatus::OutOfRange);
            } else if (want == "error") {
                EXPECT_EQ(r.status, ReadingStatus::Error);
            } else {
                ADD_FAILURE() << "expected " << want << ", got a reading (" << to_string(r.status) << ")";
            }
        } catch (const DeviceError& e) {
            if (want == "timeout") {
                EXPECT_EQ(e.kind(), DeviceErrorKind::Timeout) << e.what();
            } else if (want == "invalid") {
                EXPECT_EQ(e.kind(), DeviceErrorKind::Protocol) << e.what();
            } else {
                ADD_FAILURE() << "expected " << want << ", got: " << e.what();
            }
        }
    }
}

std::string data(const char* name) {
    return std::string(BALLBAR_GAUGE_DATA_DIR) + "/" + name;
}

void replay_serial(const char* file, const std::string& scheme, const std::string& params = "") {
    const auto steps = testing::load_stream(data(file));
    const auto ex = all_exchanges(steps);
    Replay replay(ex);
    auto g = open_gauge(scheme + ":" + replay.path() + params);
    run_steps(*g, steps, file);
    std::this_thread::sleep_for(20ms);
    EXPECT_EQ(replay.error(), "");
    EXPECT_EQ(replay.answered(), ex.size()) << "the driver did not send every request of the stream";
}

TEST(GaugeStreams, Sylvac) {
    replay_serial("sylvac.stream", "sylvac");
}

TEST(GaugeStreams, SylvacInchAndLowBattery) {
    replay_serial("sylvac_inch.stream", "sylvac");
}

TEST(GaugeStreams, Digimatic) {
    replay_serial("digimatic.stream", "digimatic");
}

TEST(GaugeStreams, ModbusThroughLibmodbus) {
    replay_serial("modbus.stream", "modbus", "?slave=1&baud=38400");
}

TEST(GaugeStreams, MitutoyoItn) {
    const auto steps = testing::load_stream(data("mitutoyo_itn.stream"));
    auto link = std::make_unique<ScriptedItn>(all_exchanges(steps));
    ScriptedItn* raw = link.get();
    auto g = make_itn_gauge(std::move(link));
    run_steps(*g, steps, "mitutoyo_itn.stream");
    EXPECT_EQ(raw->answered(), all_exchanges(steps).size());
}

}  // namespace
}  // namespace ballbar::device::gauge
