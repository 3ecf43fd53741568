// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <random>
#include <string_view>
#include <vector>

#include "ballbar/device/protocol.hpp"

using namespace ballbar::device::protocol;

namespace {

std::vector<std::uint8_t> bytes(const FrameBuffer& buf, std::size_t n) {
    return {buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(n)};
}

StreamFrame sample_stream(std::uint8_t count) {
    StreamFrame f;
    f.t0_us = 0x0123456789ABull;
    f.period_ns = 200'000;
    f.bar_temp_cC = -512;
    f.count = count;
    for (std::uint8_t i = 0; i < count; ++i) {
        f.samples[i].displacement = static_cast<std::int16_t>(i * 1000 - 9999);
        f.samples[i].flags = static_cast<std::uint8_t>(i % 8);
    }
    return f;
}

// Decodes everything in `wire`, returning frames' (type, seq) and the number of invalid results.
struct Collected {
    std::vector<std::pair<MsgType, std::uint16_t>> frames;
    std::vector<InvalidReason> invalid;
};
Collected decode_all(Decoder& d, std::span<const std::uint8_t> wire) {
    Collected c;
    while (true) {
        const auto r = d.next(wire);
        if (r.status == DecodeStatus::NeedMore) break;
        if (r.status == DecodeStatus::Frame) c.frames.emplace_back(r.frame.type, r.frame.seq);
        if (r.status == DecodeStatus::Invalid) c.invalid.push_back(r.reason);
    }
    return c;
}

}  // namespace

TEST(Crc16, CheckValue) {
    const std::string_view s = "123456789";
    EXPECT_EQ(crc16({reinterpret_cast<const std::uint8_t*>(s.data()), s.size()}), 0x29B1);
}

TEST(Cobs, RoundTripsAllLengthsAndZeroPatterns) {
    std::mt19937 rng(7);
    for (std::size_t len = 0; len <= 254; ++len) {
        for (int trial = 0; trial < 4; ++trial) {
            std::vector<std::uint8_t> in(len);
            for (auto& b : in) b = static_cast<std::uint8_t>(trial == 0 ? 0 : (trial == 1 ? 0xFF : rng() & 0x3));
            std::vector<std::uint8_t> enc(len + 2), dec(len + 1);
            const auto n = cobs_encode(in, enc);
            ASSERT_LE(n, len + 2);
            for (std::size_t i = 0; i < n; ++i) ASSERT_NE(enc[i], 0) << len;
            const auto m = cobs_decode({enc.data(), n}, dec);
            ASSERT_TRUE(m.has_value()) << len;
            ASSERT_EQ(*m, len);
            EXPECT_TRUE(std::equal(in.begin(), in.end(), dec.begin()));
        }
    }
}

TEST(Cobs, RejectsMalformed) {
    std::array<std::uint8_t, 16> out{};
    const std::array<std::uint8_t, 2> past_end{5, 1};
    EXPECT_FALSE(cobs_decode(past_end, out));
    const std::array<std::uint8_t, 3> inner_zero{3, 0, 1};
    EXPECT_FALSE(cobs_decode(inner_zero, out));
}

TEST(Codec, MaximalFramesFitOneHidReport) {
    FrameBuffer buf{};
    const auto n = encode(sample_stream(kMaxSamplesPerFrame), 65535, buf);
    EXPECT_LE(n, kMaxFrameSize);
    EXPECT_EQ(buf[n - 1], 0);
    std::array<std::uint8_t, kMaxBodySize> body{};
    body.fill(0);  // all zeros: worst case for COBS code bytes is fine, size stays bounded
    EXPECT_LE(encode_frame(MsgType::Stream, 1, body, buf), kMaxFrameSize);
    body.fill(0xAB);
    EXPECT_LE(encode_frame(MsgType::Stream, 1, body, buf), kMaxFrameSize);
    std::array<std::uint8_t, kMaxBodySize + 1> too_long{};
    EXPECT_THROW(encode_frame(MsgType::Stream, 1, too_long, buf), std::length_error);
}

TEST(Codec, StreamRoundTrip) {
    for (std::uint8_t count = 1; count <= kMaxSamplesPerFrame; ++count) {
        FrameBuffer buf{};
        const auto in = sample_stream(count);
        const auto n = encode(in, 4242, buf);
        Decoder d;
        std::span<const std::uint8_t> wire{buf.data(), n};
        const auto r = d.next(wire);
        ASSERT_EQ(r.status, DecodeStatus::Frame);
        EXPECT_TRUE(wire.empty());
        EXPECT_EQ(r.frame.type, MsgType::Stream);
        EXPECT_EQ(r.frame.seq, 4242);
        EXPECT_EQ(r.frame.version, kVersion);
        StreamFrame out;
        ASSERT_TRUE(parse_stream(r.frame.body, out));
        EXPECT_EQ(out.t0_us, in.t0_us);
        EXPECT_EQ(out.period_ns, in.period_ns);
        EXPECT_EQ(out.bar_temp_cC, in.bar_temp_cC);
        ASSERT_EQ(out.count, count);
        for (std::size_t i = 0; i < count; ++i) {
            EXPECT_EQ(out.samples[i].displacement, in.samples[i].displacement);
            EXPECT_EQ(out.samples[i].flags, in.samples[i].flags);
        }
    }
}

TEST(Codec, RequestAndReplyRoundTrips) {
    FrameBuffer buf{};
    Decoder d;
    auto decode_one = [&](std::size_t n) {
        std::span<const std::uint8_t> wire{buf.data(), n};
        auto r = d.next(wire);
        EXPECT_EQ(r.status, DecodeStatus::Frame);
        return r.frame;
    };
    IdentifyReply id;
    id.model = "BB-1E";
    id.serial = "EMU-000042";
    id.firmware = "1.2.3";
    id.calibrated_length_nm = 150'000'000;
    auto f = decode_one(encode(id, 9, buf));
    EXPECT_EQ(f.type, MsgType::IdentifyReply);
    auto id2 = parse_identify_reply(f.body);
    ASSERT_TRUE(id2);
    EXPECT_EQ(id2->model, "BB-1E");
    EXPECT_EQ(id2->serial, "EMU-000042");
    EXPECT_EQ(id2->firmware, "1.2.3");
    EXPECT_EQ(id2->calibrated_length_nm, 150'000'000u);
    EXPECT_EQ(id2->resolution_nm, 100);
    EXPECT_EQ(id2->range_nm, 1'000'000u);

    StatusReply st;
    st.battery_pct = 77;
    st.bar_temp_cC = 2134;
    st.error_flags = kStatusLowBattery | kStatusOverrun;
    st.streaming = true;
    st.sample_rate_hz = 5000;
    st.averaging = 4;
    st.referenced = true;
    f = decode_one(encode(st, 10, buf));
    auto st2 = parse_status_reply(f.body);
    ASSERT_TRUE(st2);
    EXPECT_EQ(st2->battery_pct, 77);
    EXPECT_EQ(st2->bar_temp_cC, 2134);
    EXPECT_EQ(st2->error_flags, kStatusLowBattery | kStatusOverrun);
    EXPECT_TRUE(st2->streaming);
    EXPECT_EQ(st2->sample_rate_hz, 5000);
    EXPECT_EQ(st2->averaging, 4);
    EXPECT_TRUE(st2->referenced);

    f = decode_one(encode(ConfigureBody{2500, 8}, MsgType::Configure, 11, buf));
    auto cfg = parse_configure(f.body);
    ASSERT_TRUE(cfg);
    EXPECT_EQ(cfg->sample_rate_hz, 2500);
    EXPECT_EQ(cfg->averaging, 8);

    f = decode_one(encode_heartbeat(0xDEADBEEF, 12, buf));
    EXPECT_EQ(parse_heartbeat(f.body), 0xDEADBEEFu);
    f = decode_one(encode(HeartbeatReply{7, 1ull << 40}, 12, buf));
    auto hb = parse_heartbeat_reply(f.body);
    ASSERT_TRUE(hb);
    EXPECT_EQ(hb->uptime_us, 1ull << 40);

    f = decode_one(encode(ErrorReply{ErrorCode::Busy, 0x03}, 13, buf));
    auto er = parse_error(f.body);
    ASSERT_TRUE(er);
    EXPECT_EQ(er->code, ErrorCode::Busy);
    EXPECT_EQ(er->request_type, 0x03);

    f = decode_one(encode_empty(MsgType::Start, 14, buf));
    EXPECT_EQ(f.type, MsgType::Start);
    EXPECT_TRUE(f.body.empty());
    EXPECT_FALSE(parse_identify_reply(f.body));
    EXPECT_FALSE(parse_status_reply(f.body));
}

TEST(Decoder, ByteAtATimeAndConcatenated) {
    std::vector<std::uint8_t> wire;
    FrameBuffer buf{};
    for (std::uint16_t seq = 0; seq < 50; ++seq) {
        const auto n = encode(sample_stream(static_cast<std::uint8_t>(1 + seq % 13)), seq, buf);
        auto b = bytes(buf, n);
        wire.insert(wire.end(), b.begin(), b.end());
    }
    Decoder d;
    std::vector<std::uint16_t> seqs;
    for (const auto byte : wire) {
        std::span<const std::uint8_t> one{&byte, 1};
        const auto r = d.next(one);
        ASSERT_NE(r.status, DecodeStatus::Invalid);
        if (r.status == DecodeStatus::Frame) seqs.push_back(r.frame.seq);
    }
    ASSERT_EQ(seqs.size(), 50u);
    for (std::uint16_t i = 0; i < 50; ++i) EXPECT_EQ(seqs[i], i);
    Decoder d2;
    EXPECT_EQ(decode_all(d2, wire).frames.size(), 50u);
}

TEST(Decoder, ResynchronisesAfterGarbageAndSkipsPadding) {
    FrameBuffer buf{};
    std::vector<std::uint8_t> wire(300, 0x5A);  // long garbage without delimiter: overflow
    wire.push_back(0);
    wire.insert(wire.end(), {1, 2, 3});  // short garbage
    wire.push_back(0);
    wire.insert(wire.end(), 5, 0);  // padding
    auto n = encode_empty(MsgType::Identify, 77, buf);
    auto b = bytes(buf, n);
    wire.insert(wire.end(), b.begin(), b.end());
    // Garbage glued onto the front of a frame (no delimiter between): that frame is lost, the next is not.
    wire.insert(wire.end(), {9, 9, 9});
    wire.insert(wire.end(), b.begin(), b.end());
    wire.insert(wire.end(), b.begin(), b.end());
    Decoder d;
    const auto c = decode_all(d, wire);
    ASSERT_EQ(c.frames.size(), 2u);
    EXPECT_EQ(c.frames[0].first, MsgType::Identify);
    EXPECT_EQ(c.frames[0].second, 77);
    ASSERT_EQ(c.invalid.size(), 3u);
    EXPECT_EQ(c.invalid[0], InvalidReason::TooLong);
    EXPECT_EQ(d.frames(), 2u);
    EXPECT_EQ(d.invalid(), 3u);
}

TEST(Decoder, EveryFlippedBitIsCaught) {
    FrameBuffer buf{};
    const auto n = encode(sample_stream(13), 3, buf);
    for (std::size_t i = 0; i + 1 < n; ++i) {
        for (int bit = 0; bit < 8; ++bit) {
            auto wire = bytes(buf, n);
            wire[i] = static_cast<std::uint8_t>(wire[i] ^ (1u << bit));
            // A following good frame must always come through.
            auto good = bytes(buf, n);
            wire.insert(wire.end(), good.begin(), good.end());
            Decoder d;
            const auto c = decode_all(d, wire);
            ASSERT_GE(c.frames.size(), 1u) << i << ":" << bit;
            // The corrupted frame is never accepted as a frame: one frame only, the good one.
            EXPECT_EQ(c.frames.size(), 1u) << i << ":" << bit;
            EXPECT_GE(c.invalid.size(), 1u) << i << ":" << bit;
        }
    }
}

TEST(Decoder, CrcErrorReported) {
    FrameBuffer buf{};
    const auto n = encode_empty(MsgType::Status, 1, buf);
    auto wire = bytes(buf, n);
    // Rebuild with a wrong CRC but valid COBS: payload bytes changed before encoding.
    std::array<std::uint8_t, 6> payload{kVersion, 0x02, 1, 0, 0x12, 0x34};
    std::array<std::uint8_t, 8> enc{};
    const auto m = cobs_encode(payload, enc);
    std::vector<std::uint8_t> bad(enc.begin(), enc.begin() + static_cast<std::ptrdiff_t>(m));
    bad.push_back(0);
    Decoder d;
    const auto c = decode_all(d, bad);
    ASSERT_EQ(c.invalid.size(), 1u);
    EXPECT_EQ(c.invalid[0], InvalidReason::Crc);
    Decoder d2;
    EXPECT_EQ(decode_all(d2, wire).frames.size(), 1u);
}

TEST(Decoder, ParseStreamRejectsInconsistentCount) {
    FrameBuffer buf{};
    const auto n = encode(sample_stream(5), 1, buf);
    Decoder d;
    std::span<const std::uint8_t> wire{buf.data(), n};
    auto r = d.next(wire);
    ASSERT_EQ(r.status, DecodeStatus::Frame);
    StreamFrame out;
    EXPECT_FALSE(parse_stream(r.frame.body.first(r.frame.body.size() - 3), out));
    EXPECT_FALSE(parse_stream(r.frame.body.first(10), out));
}

TEST(Codec, IdentifyReplyWithAndWithoutCalibrationDate) {
    IdentifyReply id;
    id.model = "BB-1E";
    id.calibrated_length_nm = 100'000'000;
    id.calibration_date = 20251130;
    FrameBuffer buf{};
    Decoder d;
    std::span<const std::uint8_t> wire{buf.data(), encode(id, 3, buf)};
    const auto r = d.next(wire);
    ASSERT_EQ(r.status, DecodeStatus::Frame);
    ASSERT_EQ(r.frame.body.size(), 47u);
    const auto back = parse_identify_reply(r.frame.body);
    ASSERT_TRUE(back);
    EXPECT_EQ(back->calibration_date, 20251130u);
    // Firmware from before the date: the 43 bytes up to range_nm.
    const auto old = parse_identify_reply(r.frame.body.first(43));
    ASSERT_TRUE(old);
    EXPECT_EQ(old->calibration_date, 0u);
    EXPECT_EQ(old->calibrated_length_nm, 100'000'000u);
    EXPECT_FALSE(parse_identify_reply(r.frame.body.first(45)));
    std::vector<std::uint8_t> bad(r.frame.body.begin(), r.frame.body.end());
    bad[46] = 0xFF;  // not a date
    EXPECT_FALSE(parse_identify_reply(bad));
}
