// SPDX-License-Identifier: MIT
// Stream faults the emulator does not make, as crafted byte streams through the real decoder and driver:
// a replayed stream frame (stored once, not counted as loss), a frame of another protocol version
// (skipped and counted), and both together over a real TCP link. The device's frames are built here from
// docs/protocol.md alone (own COBS, own bitwise CRC), not with the codec under test.
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cstring>
#include <deque>
#include <thread>
#include <vector>

#include "ballbar/device/emulator_host.hpp"
#include "ballbar/device/instrument.hpp"
#include "ballbar/device/protocol.hpp"
#include "ballbar/device/uri.hpp"

using namespace ballbar;
using namespace ballbar::device;
using namespace std::chrono_literals;

namespace {

using Bytes = std::vector<std::uint8_t>;

// ---- the published frame format, written independently ----

std::uint16_t crc_bitwise(const Bytes& data) {
    std::uint16_t crc = 0xFFFF;
    for (const std::uint8_t b : data) {
        crc ^= static_cast<std::uint16_t>(b << 8);
        for (int i = 0; i < 8; ++i)
            crc =
                (crc & 0x8000) ? static_cast<std::uint16_t>((crc << 1) ^ 0x1021) : static_cast<std::uint16_t>(crc << 1);
    }
    return crc;
}

Bytes cobs(const Bytes& in) {
    Bytes out(1, 0);
    std::size_t code_at = 0;
    for (const std::uint8_t b : in) {
        if (b == 0) {
            out[code_at] = static_cast<std::uint8_t>(out.size() - code_at);
            code_at = out.size();
            out.push_back(0);
        } else {
            out.push_back(b);
        }
    }
    out[code_at] = static_cast<std::uint8_t>(out.size() - code_at);
    return out;
}

void put_le(Bytes& b, std::uint64_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

Bytes wire(std::uint8_t version, std::uint8_t type, std::uint16_t seq, const Bytes& body) {
    Bytes p{version, type};
    put_le(p, seq, 2);
    p.insert(p.end(), body.begin(), body.end());
    put_le(p, crc_bitwise(p), 2);
    Bytes w = cobs(p);
    w.push_back(0);
    return w;
}

constexpr int kPerFrame = 13;
constexpr std::uint64_t kPeriodUs = 1000;  // 1 kHz

/// Stream frame number `n` of a steady 1 kHz stream: its samples' displacement encodes their index.
Bytes stream_frame(std::uint16_t seq, std::uint64_t n, std::uint8_t version = 1) {
    Bytes b;
    put_le(b, 5'000 + n * kPerFrame * kPeriodUs, 8);  // t0_us
    put_le(b, kPeriodUs * 1000, 4);                   // period_ns
    put_le(b, 2012, 2);                               // 20.12 °C
    b.push_back(kPerFrame);
    for (int i = 0; i < kPerFrame; ++i) {
        put_le(b, static_cast<std::uint16_t>(n * kPerFrame + static_cast<std::uint64_t>(i)), 2);
        b.push_back(0);
    }
    return wire(version, 0x10, seq, b);
}

Bytes identify_reply(std::uint16_t seq, std::uint8_t version = 1) {
    Bytes b{1};
    for (const char* s : {"CRAFTED", "CR0001"}) {
        for (int i = 0; i < 12; ++i) b.push_back(static_cast<std::uint8_t>(i < static_cast<int>(strlen(s)) ? s[i] : 0));
    }
    for (int i = 0; i < 8; ++i) b.push_back(static_cast<std::uint8_t>(i < 3 ? "9.9"[i] : 0));
    put_le(b, 100'000'000, 4);  // 100 mm
    put_le(b, 100, 2);
    put_le(b, 1'000'000, 4);
    put_le(b, 20260301, 4);  // calibrated on 2026-03-01
    return wire(version, 0x81, seq, b);
}

/// A device that answers Identify, Start and Stop and, after StartReply, sends a scripted stream.
/// `reply_version` lets it answer in another protocol version.
class CraftedDevice : public DeviceEndpoint {
  public:
    explicit CraftedDevice(std::vector<Bytes> stream, std::uint8_t reply_version = 1)
        : stream_(std::move(stream)), version_(reply_version) {}

    void on_host_bytes(std::span<const std::uint8_t> data) override {
        while (!data.empty()) {
            const auto r = decoder_.next(data);
            if (r.status != protocol::DecodeStatus::Frame) continue;
            const auto type = static_cast<std::uint8_t>(r.frame.type);
            if (type == 0x01) {
                append(identify_reply(r.frame.seq, version_));
            } else if (type == 0x04 || type == 0x05) {
                append(wire(version_, static_cast<std::uint8_t>(type | 0x80), r.frame.seq, {}));
                if (type == 0x04) {
                    for (const auto& f : stream_) append(f);
                }
            } else if (type == 0x07) {
                Bytes body(r.frame.body.begin(), r.frame.body.end());
                put_le(body, 0, 8);
                append(wire(version_, 0x87, r.frame.seq, body));
            }
        }
    }
    std::size_t take_device_bytes(std::span<std::uint8_t> out) override {
        std::size_t n = 0;
        while (n < out.size() && !out_.empty()) {
            out[n++] = out_.front();
            out_.pop_front();
        }
        return n;
    }

  private:
    void append(const Bytes& b) { out_.insert(out_.end(), b.begin(), b.end()); }
    std::vector<Bytes> stream_;
    std::uint8_t version_;
    protocol::Decoder decoder_;
    std::deque<std::uint8_t> out_;
};

/// In-process link to a CraftedDevice; delivers its bytes in small pieces (frames split across reads).
class CraftedLink : public Transport {
  public:
    explicit CraftedLink(CraftedDevice& d) : d_(d) {}
    void write(std::span<const std::uint8_t> data, std::chrono::milliseconds) override { d_.on_host_bytes(data); }
    std::size_t read(std::span<std::uint8_t> data, std::chrono::milliseconds) override {
        return d_.take_device_bytes(data.first(std::min<std::size_t>(data.size(), 23)));
    }
    std::string uri() const override { return "crafted:"; }

  private:
    CraftedDevice& d_;
};

std::vector<analysis::BarSample> drain(Instrument& inst, std::size_t at_most_polls = 200) {
    std::vector<analysis::BarSample> all, buf(1024);
    for (std::size_t i = 0; i < at_most_polls; ++i) {
        inst.poll(5ms);
        const std::size_t n = inst.read_samples(buf);
        all.insert(all.end(), buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(n));
    }
    return all;
}

/// Each sample once, in order: displacement index k is sample k of the crafted stream.
void expect_each_once(const std::vector<analysis::BarSample>& s, const std::vector<std::uint64_t>& frames) {
    std::vector<std::int32_t> want;
    for (const auto f : frames) {
        for (int i = 0; i < kPerFrame; ++i) want.push_back(static_cast<std::int32_t>(f * kPerFrame) + i);
    }
    ASSERT_EQ(s.size(), want.size());
    for (std::size_t i = 0; i < s.size(); ++i) {
        ASSERT_EQ(s[i].displacement_nm, want[i] * 100) << i;
        if (i > 0) {
            ASSERT_GT(s[i].device_time_us, s[i - 1].device_time_us) << i;
        }
    }
}

}  // namespace

TEST(StreamFaults, ReplayedFrameIsStoredOnceAndNotCountedAsLoss) {
    std::vector<Bytes> stream;
    for (std::uint16_t k = 0; k < 10; ++k) stream.push_back(stream_frame(k, k));
    stream.push_back(stream_frame(9, 9));  // the last frame again (a link that repeats a packet)
    stream.push_back(stream_frame(10, 10));
    stream.push_back(stream_frame(4, 4));  // an old one, much later
    stream.push_back(stream_frame(11, 11));
    CraftedDevice dev(stream);
    Instrument inst(std::make_unique<CraftedLink>(dev));
    const auto& info = inst.identify();
    EXPECT_EQ(info.calibration_date, "2026-03-01");
    inst.start_streaming();
    const auto s = drain(inst);
    expect_each_once(s, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11});
    for (const auto& x : s) EXPECT_EQ(x.flags & kSampleAfterGap, 0);
    EXPECT_EQ(inst.stats().replayed_frames, 2u);
    EXPECT_EQ(inst.stats().lost_frames, 0u);
    EXPECT_EQ(inst.stats().gaps, 0u);
}

TEST(StreamFaults, ReplayAfterARealGapCountsOnlyTheGap) {
    std::vector<Bytes> stream;
    for (std::uint16_t k = 0; k < 4; ++k) stream.push_back(stream_frame(k, k));
    // frames 4 and 5 are lost; frame 3 comes again; then the stream goes on
    stream.push_back(stream_frame(3, 3));
    for (std::uint16_t k = 6; k < 9; ++k) stream.push_back(stream_frame(k, k));
    CraftedDevice dev(stream);
    Instrument inst(std::make_unique<CraftedLink>(dev));
    inst.identify();
    inst.start_streaming();
    const auto s = drain(inst);
    expect_each_once(s, {0, 1, 2, 3, 6, 7, 8});
    EXPECT_EQ(inst.stats().lost_frames, 2u);
    EXPECT_EQ(inst.stats().gaps, 1u);
    EXPECT_EQ(inst.stats().replayed_frames, 1u);
    ASSERT_EQ(s.size(), 7u * kPerFrame);
    EXPECT_NE(s[4 * kPerFrame].flags & kSampleAfterGap, 0) << "the first sample after the gap is marked";
}

TEST(StreamFaults, UnknownVersionFrameIsSkippedAndCounted) {
    std::vector<Bytes> stream;
    for (std::uint16_t k = 0; k < 5; ++k) stream.push_back(stream_frame(k, k));
    stream.push_back(stream_frame(5, 99, 2));  // an extra frame of protocol version 2
    for (std::uint16_t k = 5; k < 8; ++k) stream.push_back(stream_frame(k, k));
    stream.push_back(stream_frame(8, 8, 7));  // version 7 in place of frame 8: its samples are lost
    for (std::uint16_t k = 9; k < 11; ++k) stream.push_back(stream_frame(k, k));
    CraftedDevice dev(stream);
    Instrument inst(std::make_unique<CraftedLink>(dev));
    inst.identify();
    inst.start_streaming();
    const auto s = drain(inst);
    expect_each_once(s, {0, 1, 2, 3, 4, 5, 6, 7, 9, 10});
    EXPECT_EQ(inst.stats().unknown_version_frames, 2u);
    EXPECT_EQ(inst.stats().unknown_version, 7);
    EXPECT_EQ(inst.stats().lost_frames, 1u);
    EXPECT_NE(s[8 * kPerFrame].flags & kSampleAfterGap, 0);
    inst.stop_streaming();  // the link still works
}

TEST(StreamFaults, AnInstrumentAnsweringInAnotherVersionIsNamed) {
    CraftedDevice dev({}, 2);
    Instrument inst(std::make_unique<CraftedLink>(dev), InstrumentOptions{.reply_timeout = 20ms, .attempts = 2});
    try {
        inst.identify();
        FAIL() << "identified an instrument that answers in protocol version 2";
    } catch (const DeviceError& e) {
        EXPECT_EQ(e.kind(), DeviceErrorKind::Protocol);
        EXPECT_NE(std::string(e.what()).find("protocol version 2"), std::string::npos) << e.what();
    }
    EXPECT_EQ(inst.stats().unknown_version_frames, 2u);
}

TEST(StreamFaults, ReplayAndForeignVersionOverTcp) {
    std::vector<Bytes> stream;
    for (std::uint16_t k = 0; k < 6; ++k) stream.push_back(stream_frame(k, k));
    stream.push_back(stream_frame(5, 5));
    stream.push_back(stream_frame(6, 6, 3));
    stream.push_back(stream_frame(6, 6));
    stream.push_back(stream_frame(2, 2));
    for (std::uint16_t k = 7; k < 9; ++k) stream.push_back(stream_frame(k, k));
    CraftedDevice dev(stream);
    TcpListener listener(0);
    std::atomic<bool> stop{false};
    std::thread server([&] {
        const int fd = listener.accept(5000ms);
        if (fd < 0) return;
        std::array<std::uint8_t, 512> buf{};
        while (!stop) {
            pollfd p{fd, POLLIN, 0};
            if (::poll(&p, 1, 5) > 0) {
                const ssize_t n = ::read(fd, buf.data(), buf.size());
                if (n <= 0) break;
                dev.on_host_bytes({buf.data(), static_cast<std::size_t>(n)});
            }
            // One byte short of a frame at a time: TCP may split anywhere.
            std::size_t n;
            while ((n = dev.take_device_bytes({buf.data(), 37})) > 0) {
                if (::send(fd, buf.data(), n, MSG_NOSIGNAL) != static_cast<ssize_t>(n)) break;
            }
        }
        ::close(fd);
    });
    {
        Instrument inst(open_transport("tcp:127.0.0.1:" + std::to_string(listener.port())));
        inst.identify();
        inst.start_streaming();
        std::vector<analysis::BarSample> s, buf(1024);
        const auto until = std::chrono::steady_clock::now() + 5s;
        while (s.size() < 9 * kPerFrame && std::chrono::steady_clock::now() < until) {
            inst.poll(20ms);
            const std::size_t n = inst.read_samples(buf);
            s.insert(s.end(), buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(n));
        }
        for (int i = 0; i < 5; ++i) inst.poll(10ms);  // nothing more may come
        const std::size_t n = inst.read_samples(buf);
        s.insert(s.end(), buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(n));
        expect_each_once(s, {0, 1, 2, 3, 4, 5, 6, 7, 8});
        EXPECT_EQ(inst.stats().replayed_frames, 2u);
        EXPECT_EQ(inst.stats().unknown_version_frames, 1u);
        EXPECT_EQ(inst.stats().lost_frames, 0u);
        inst.stop_streaming();
    }
    stop = true;
    server.join();
}

TEST(StreamFaults, CalibrationDateTextAndNumber) {
    EXPECT_EQ(protocol::parse_calibration_date("2026-03-01"), 20260301u);
    EXPECT_EQ(protocol::parse_calibration_date("2024-02-29"), 20240229u);
    EXPECT_EQ(protocol::parse_calibration_date(""), 0u);
    EXPECT_FALSE(protocol::parse_calibration_date("2025-02-29"));
    EXPECT_FALSE(protocol::parse_calibration_date("2026-13-01"));
    EXPECT_FALSE(protocol::parse_calibration_date("2026-3-01"));
    EXPECT_EQ(protocol::format_calibration_date(20260301), "2026-03-01");
    EXPECT_EQ(protocol::format_calibration_date(0), "");
    EXPECT_EQ(protocol::format_calibration_date(20261340), "");
}
