// SPDX-License-Identifier: MIT
// The emulator behind real links — a pseudo-terminal (termios) and loopback TCP — driven by the real
// driver, including a simulated disconnect and reconnect; and the URI factory.
#include <gtest/gtest.h>

#include <atomic>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <thread>

#include "ballbar/device/emulator_host.hpp"
#include "ballbar/device/instrument.hpp"
#include "ballbar/device/serial.hpp"
#include "ballbar/device/tcp.hpp"
#include "ballbar/device/uri.hpp"

using namespace ballbar;
using namespace ballbar::device;
using namespace std::chrono_literals;

namespace {

EmulatorConfig fast_config() {
    EmulatorConfig c;
    c.seed = 3;
    c.instrument.sample_rate_hz = 5000;
    return c;
}

/// Runs an emulator on ptys in a background thread; hands out the current pty path.
class PtyFixture {
  public:
    explicit PtyFixture(EmulatorConfig cfg, Pacing pacing = Pacing::Simulated) : emu_(std::move(cfg)) {
        HostOptions opt;
        opt.pacing = pacing;
        opt.stop = &stop_;
        thread_ = std::thread([this, opt] {
            EmulatorHost host(emu_, opt);
            host.run_pty([this](const std::string& path) {
                std::lock_guard lock(m_);
                path_ = path;
                ++ptys_;
                cv_.notify_all();
            });
        });
    }
    ~PtyFixture() {
        stop_ = true;
        thread_.join();
    }
    std::string wait_pty(int n) {
        std::unique_lock lock(m_);
        cv_.wait_for(lock, 10s, [&] { return ptys_ >= n; });
        return ptys_ >= n ? path_ : std::string();
    }

  private:
    Emulator emu_;
    std::atomic<bool> stop_{false};
    std::mutex m_;
    std::condition_variable cv_;
    std::string path_;
    int ptys_ = 0;
    std::thread thread_;
};

std::size_t stream(Instrument& inst, std::size_t wanted, std::vector<analysis::BarSample>& out) {
    out.resize(wanted);
    std::size_t have = 0;
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    while (have < wanted && std::chrono::steady_clock::now() < deadline) {
        inst.poll(50ms);
        have += inst.read_samples(std::span(out).subspan(have));
    }
    out.resize(have);
    return have;
}

}  // namespace

TEST(PtyLink, LibserialportRefusesABarePtySoTermiosIsUsed) {
    PtyFixture fx(fast_config());
    const auto path = fx.wait_pty(1);
    ASSERT_FALSE(path.empty());
    EXPECT_TRUE(is_pseudo_terminal(path));
    EXPECT_THROW(open_libserialport_transport(path), DeviceError);
    auto t = open_serial_transport(path);
    EXPECT_EQ(t->uri(), "serial:" + path);
}

TEST(PtyLink, StreamsWithoutLossAtFullSpeed) {
    PtyFixture fx(fast_config());
    Instrument inst(open_transport("serial:" + fx.wait_pty(1)));
    EXPECT_EQ(inst.identify().serial, "EMU00001");
    inst.configure(5000, 1);
    inst.start_streaming();
    std::vector<analysis::BarSample> s;
    ASSERT_EQ(stream(inst, 50000, s), 50000u);
    inst.stop_streaming();
    EXPECT_EQ(inst.stats().lost_frames, 0u);
    EXPECT_EQ(inst.stats().invalid_frames, 0u);
    for (std::size_t i = 1; i < s.size(); ++i) ASSERT_EQ(s[i].device_time_us - s[i - 1].device_time_us, 200u);
}

/// As fast as the host reads, 20 s of the instrument's clock pass in a fraction of a second: its
/// watchdog (2 s here) must count the host's silence on the wall clock, or it stops the stream of a
/// host that is reading all the time (issue 24: `emulate --fast` and measure's "sends nothing").
TEST(PtyLink, AsFastAsTheHostReadsTheWatchdogCountsWallClockSilence) {
    auto cfg = fast_config();
    cfg.instrument.watchdog_s = 2.0;
    PtyFixture fx(cfg);
    Instrument inst(open_transport("serial:" + fx.wait_pty(1)));
    inst.identify();
    inst.configure(5000, 1);
    inst.start_streaming();
    std::vector<analysis::BarSample> s;
    ASSERT_EQ(stream(inst, 100000, s), 100000u)
        << "the stream stopped after " << 1e-6 * static_cast<double>(s.back().device_time_us) << " s";
    // A host that goes quiet for longer than the watchdog, in wall-clock time, is still let go.
    std::this_thread::sleep_for(3s);
    EXPECT_FALSE(inst.status().streaming);
}

TEST(PtyLink, DisconnectIsReportedAndANewPtyComesBack) {
    auto cfg = fast_config();
    // Late enough that the as-fast-as-possible host (which runs ~1.3 s of samples ahead of the reader)
    // cannot reach it before StartReply has been delivered.
    cfg.faults.disconnect_at_s = 5.0;
    cfg.faults.disconnect_s = 0.2;
    PtyFixture fx(cfg);
    Instrument inst(open_transport("serial:" + fx.wait_pty(1)));
    inst.identify();
    inst.start_streaming();
    std::vector<analysis::BarSample> s;
    try {
        stream(inst, 1'000'000, s);
        FAIL() << "no disconnect reported";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::Disconnected) << e.what();
    }
    const auto path2 = fx.wait_pty(2);
    ASSERT_FALSE(path2.empty());
    Instrument again(open_transport("serial:" + path2));
    again.identify();
    again.start_streaming();
    ASSERT_EQ(stream(again, 5000, s), 5000u);
    EXPECT_EQ(again.stats().lost_frames, 0u);
}

TEST(TcpLink, StreamsDisconnectsAndReconnects) {
    auto cfg = fast_config();
    cfg.faults.disconnect_at_s = 5.0;  // see above
    cfg.faults.disconnect_s = 0.3;
    Emulator emu(cfg);
    TcpListener listener(0);
    std::atomic<bool> stop{false};
    std::thread server([&] {
        HostOptions opt;
        opt.pacing = Pacing::Simulated;
        opt.stop = &stop;
        EmulatorHost host(emu, opt);
        host.run_tcp(listener);
    });
    struct Joiner {
        std::atomic<bool>& stop;
        std::thread& thread;
        ~Joiner() {
            stop = true;
            thread.join();
        }
    } joiner{stop, server};
    const std::string uri = "tcp:127.0.0.1:" + std::to_string(listener.port());
    {
        Instrument inst(open_transport(uri));
        EXPECT_EQ(inst.transport().uri(), uri);
        inst.identify();
        inst.start_streaming();
        std::vector<analysis::BarSample> s;
        try {
            stream(inst, 1'000'000, s);
            ADD_FAILURE() << "no disconnect reported";
        } catch (const DeviceError& e) {
            EXPECT_EQ(e.kind(), DeviceErrorKind::Disconnected) << e.what();
        }
    }
    // Comes back on the same port.
    std::unique_ptr<Instrument> inst2;
    for (int i = 0; i < 100 && !inst2; ++i) {
        try {
            auto t = open_transport(uri);
            auto candidate = std::make_unique<Instrument>(std::move(t), InstrumentOptions{.reply_timeout = 1000ms});
            candidate->identify();
            inst2 = std::move(candidate);
        } catch (const DeviceError&) {
            std::this_thread::sleep_for(20ms);
        }
    }
    ASSERT_TRUE(inst2);
    inst2->start_streaming();
    std::vector<analysis::BarSample> s;
    EXPECT_EQ(stream(*inst2, 20000, s), 20000u);
    EXPECT_EQ(inst2->stats().lost_frames, 0u);
}

TEST(TcpLink, RefusedConnectionIsNotFound) {
    std::uint16_t port = 0;
    {
        TcpListener l(0);
        port = l.port();
    }
    try {
        open_tcp_transport("127.0.0.1", port, 500ms);
        FAIL();
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::NotFound) << e.what();
    }
}

TEST(Uri, ParsesEveryScheme) {
    auto d = parse_device_uri("serial:/dev/ttyACM0");
    EXPECT_EQ(d.scheme, DeviceUri::Scheme::Serial);
    EXPECT_EQ(d.path, "/dev/ttyACM0");
    d = parse_device_uri("tcp:127.0.0.1:5555");
    EXPECT_EQ(d.scheme, DeviceUri::Scheme::Tcp);
    EXPECT_EQ(d.host, "127.0.0.1");
    EXPECT_EQ(d.port, 5555);
    d = parse_device_uri("tcp:[::1]:80");
    EXPECT_EQ(d.host, "::1");
    d = parse_device_uri("usb:1209:B0B0:BB0042");
    EXPECT_EQ(d.scheme, DeviceUri::Scheme::Usb);
    EXPECT_EQ(d.vid, 0x1209);
    EXPECT_EQ(d.pid, 0xB0B0);
    EXPECT_EQ(d.serial, "BB0042");
    d = parse_device_uri("hid:1209:3");
    EXPECT_EQ(d.scheme, DeviceUri::Scheme::Hid);
    EXPECT_EQ(d.pid, 3);
    EXPECT_TRUE(d.serial.empty());
    d = parse_device_uri("emulator:");
    EXPECT_EQ(d.scheme, DeviceUri::Scheme::Emulator);
    EXPECT_TRUE(d.path.empty());
    for (const char* badu : {"ttyACM0", "serial:", "tcp:host", "tcp:host:0", "tcp:host:99999", "usb:12345:1",
                             "usb:zz:1", "usb:1209", "ftp:x"}) {
        EXPECT_THROW(parse_device_uri(badu), std::invalid_argument) << badu;
    }
}

TEST(Uri, OpensAndReportsErrors) {
    try {
        open_transport("serial:/dev/does-not-exist-ballbar");
        FAIL();
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::NotFound) << e.what();
    }
    Instrument inst(open_transport("emulator:"));
    EXPECT_EQ(inst.identify().model, "BB-1E");
    EXPECT_THROW(open_transport("emulator:/nonexistent/config.json"), std::invalid_argument);
}
