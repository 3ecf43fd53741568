// SPDX-License-Identifier: MIT
// Protocol v1 codec: COBS framing, CRC-16/CCITT-FALSE, message bodies (docs/protocol.md).
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "ballbar/device/protocol.hpp"

namespace ballbar::device::protocol {

namespace {

constexpr std::array<std::uint16_t, 256> make_crc_table() {
    std::array<std::uint16_t, 256> table{};
    for (unsigned i = 0; i < 256; ++i) {
        unsigned crc = i << 8;
        for (int bit = 0; bit < 8; ++bit) crc = (crc & 0x8000u) ? ((crc << 1) ^ 0x1021u) : (crc << 1);
        table[i] = static_cast<std::uint16_t>(crc & 0xFFFFu);
    }
    return table;
}
constexpr auto kCrcTable = make_crc_table();

// Little-endian body writer/reader over fixed buffers.
struct Writer {
    std::array<std::uint8_t, kMaxBodySize> buf{};
    std::size_t n = 0;
    void u8(std::uint8_t v) { buf[n++] = v; }
    void u16(std::uint16_t v) {
        u8(static_cast<std::uint8_t>(v & 0xFFu));
        u8(static_cast<std::uint8_t>(v >> 8));
    }
    void i16(std::int16_t v) { u16(static_cast<std::uint16_t>(v)); }
    void u32(std::uint32_t v) {
        u16(static_cast<std::uint16_t>(v & 0xFFFFu));
        u16(static_cast<std::uint16_t>(v >> 16));
    }
    void u64(std::uint64_t v) {
        u32(static_cast<std::uint32_t>(v & 0xFFFFFFFFu));
        u32(static_cast<std::uint32_t>(v >> 32));
    }
    void str(std::string_view s, std::size_t width) {
        for (std::size_t i = 0; i < width; ++i) u8(i < s.size() ? static_cast<std::uint8_t>(s[i]) : 0);
    }
    std::span<const std::uint8_t> span() const { return {buf.data(), n}; }
};

struct Reader {
    std::span<const std::uint8_t> b;
    std::size_t n = 0;
    std::uint8_t u8() { return b[n++]; }
    std::uint16_t u16() {
        const std::uint16_t lo = u8();
        return static_cast<std::uint16_t>(lo | (u8() << 8));
    }
    std::int16_t i16() { return static_cast<std::int16_t>(u16()); }
    std::uint32_t u32() {
        const std::uint32_t lo = u16();
        return lo | (static_cast<std::uint32_t>(u16()) << 16);
    }
    std::uint64_t u64() {
        const std::uint64_t lo = u32();
        return lo | (static_cast<std::uint64_t>(u32()) << 32);
    }
    std::string str(std::size_t width) {
        std::string s;
        for (std::size_t i = 0; i < width; ++i) {
            const char c = static_cast<char>(u8());
            if (c != '\0' && s.size() == i) s.push_back(c);
        }
        return s;
    }
};

}  // namespace

std::uint16_t crc16(std::span<const std::uint8_t> data, std::uint16_t crc) {
    for (const std::uint8_t byte : data) {
        crc = static_cast<std::uint16_t>((crc << 8) ^ kCrcTable[((crc >> 8) ^ byte) & 0xFFu]);
    }
    return crc;
}

std::string_view to_string(MsgType type) {
    switch (type) {
        case MsgType::Identify:
            return "Identify";
        case MsgType::Status:
            return "Status";
        case MsgType::Configure:
            return "Configure";
        case MsgType::Start:
            return "Start";
        case MsgType::Stop:
            return "Stop";
        case MsgType::SetReference:
            return "SetReference";
        case MsgType::Heartbeat:
            return "Heartbeat";
        case MsgType::IdentifyReply:
            return "IdentifyReply";
        case MsgType::StatusReply:
            return "StatusReply";
        case MsgType::ConfigureReply:
            return "ConfigureReply";
        case MsgType::StartReply:
            return "StartReply";
        case MsgType::StopReply:
            return "StopReply";
        case MsgType::SetReferenceReply:
            return "SetReferenceReply";
        case MsgType::HeartbeatReply:
            return "HeartbeatReply";
        case MsgType::Stream:
            return "Stream";
        case MsgType::Error:
            return "Error";
    }
    return "unknown";
}

std::string_view to_string(ErrorCode code) {
    switch (code) {
        case ErrorCode::UnknownType:
            return "unknown request type";
        case ErrorCode::BadLength:
            return "bad body length";
        case ErrorCode::OutOfRange:
            return "argument out of range";
        case ErrorCode::Busy:
            return "busy (not allowed while streaming)";
        case ErrorCode::UnsupportedVersion:
            return "unsupported protocol version";
        case ErrorCode::HardwareFault:
            return "hardware fault";
    }
    return "unknown error code";
}

std::string_view to_string(InvalidReason reason) {
    switch (reason) {
        case InvalidReason::None:
            return "none";
        case InvalidReason::TooLong:
            return "frame too long";
        case InvalidReason::Cobs:
            return "malformed COBS";
        case InvalidReason::TooShort:
            return "frame too short";
        case InvalidReason::Crc:
            return "CRC mismatch";
    }
    return "?";
}

// ---- COBS ----

std::size_t cobs_encode(std::span<const std::uint8_t> in, std::span<std::uint8_t> out) {
    std::size_t code_at = 0;
    std::size_t o = 1;
    std::uint8_t code = 1;
    for (const std::uint8_t byte : in) {
        if (byte == 0) {
            out[code_at] = code;
            code_at = o++;
            code = 1;
        } else {
            out[o++] = byte;
            if (++code == 0xFF) {
                out[code_at] = code;
                code_at = o++;
                code = 1;
            }
        }
    }
    out[code_at] = code;
    return o;
}

std::optional<std::size_t> cobs_decode(std::span<const std::uint8_t> in, std::span<std::uint8_t> out) {
    std::size_t i = 0;
    std::size_t o = 0;
    const std::size_t n = in.size();
    while (i < n) {
        const std::uint8_t code = in[i++];
        if (code == 0) return std::nullopt;
        const std::size_t run = code - 1u;
        if (run > n - i || o + run > out.size()) return std::nullopt;
        for (std::size_t k = 0; k < run; ++k) {
            const std::uint8_t byte = in[i + k];
            if (byte == 0) return std::nullopt;
            out[o + k] = byte;
        }
        i += run;
        o += run;
        if (code != 0xFF && i < n) {
            if (o >= out.size()) return std::nullopt;
            out[o++] = 0;
        }
    }
    return o;
}

// ---- encoding ----

std::size_t encode_frame(MsgType type, std::uint16_t seq, std::span<const std::uint8_t> body, FrameBuffer& out,
                         std::uint8_t version) {
    if (body.size() > kMaxBodySize) throw std::length_error("protocol frame body longer than 56 bytes");
    std::array<std::uint8_t, kMaxPayloadSize> payload{};
    payload[0] = version;
    payload[1] = static_cast<std::uint8_t>(type);
    payload[2] = static_cast<std::uint8_t>(seq & 0xFFu);
    payload[3] = static_cast<std::uint8_t>(seq >> 8);
    if (!body.empty()) std::memcpy(payload.data() + kHeaderSize, body.data(), body.size());
    const std::size_t n = kHeaderSize + body.size();
    const std::uint16_t crc = crc16({payload.data(), n});
    payload[n] = static_cast<std::uint8_t>(crc & 0xFFu);
    payload[n + 1] = static_cast<std::uint8_t>(crc >> 8);
    const std::size_t encoded = cobs_encode({payload.data(), n + kCrcSize}, {out.data(), kMaxEncodedSize});
    out[encoded] = 0;
    return encoded + 1;
}

std::size_t encode_empty(MsgType type, std::uint16_t seq, FrameBuffer& out) {
    return encode_frame(type, seq, {}, out);
}

std::size_t encode(const IdentifyReply& m, std::uint16_t seq, FrameBuffer& out) {
    Writer w;
    w.u8(m.protocol_version);
    w.str(m.model, 12);
    w.str(m.serial, 12);
    w.str(m.firmware, 8);
    w.u32(m.calibrated_length_nm);
    w.u16(m.resolution_nm);
    w.u32(m.range_nm);
    w.u32(m.calibration_date);
    return encode_frame(MsgType::IdentifyReply, seq, w.span(), out);
}

std::size_t encode(const StatusReply& m, std::uint16_t seq, FrameBuffer& out) {
    Writer w;
    w.u8(m.battery_pct);
    w.u16(m.battery_mV);
    w.i16(m.bar_temp_cC);
    w.u16(m.error_flags);
    w.u8(m.streaming ? 1 : 0);
    w.u16(m.sample_rate_hz);
    w.u8(m.averaging);
    w.u8(m.referenced ? 1 : 0);
    return encode_frame(MsgType::StatusReply, seq, w.span(), out);
}

std::size_t encode(const ConfigureBody& m, MsgType type, std::uint16_t seq, FrameBuffer& out) {
    Writer w;
    w.u16(m.sample_rate_hz);
    w.u8(m.averaging);
    return encode_frame(type, seq, w.span(), out);
}

std::size_t encode_heartbeat(std::uint32_t token, std::uint16_t seq, FrameBuffer& out) {
    Writer w;
    w.u32(token);
    return encode_frame(MsgType::Heartbeat, seq, w.span(), out);
}

std::size_t encode(const HeartbeatReply& m, std::uint16_t seq, FrameBuffer& out) {
    Writer w;
    w.u32(m.token);
    w.u64(m.uptime_us);
    return encode_frame(MsgType::HeartbeatReply, seq, w.span(), out);
}

std::size_t encode(const StreamFrame& m, std::uint16_t seq, FrameBuffer& out) {
    if (m.count == 0 || m.count > kMaxSamplesPerFrame) throw std::length_error("stream frame needs 1..13 samples");
    Writer w;
    w.u64(m.t0_us);
    w.u32(m.period_ns);
    w.i16(m.bar_temp_cC);
    w.u8(m.count);
    for (std::size_t i = 0; i < m.count; ++i) {
        w.i16(m.samples[i].displacement);
        w.u8(m.samples[i].flags);
    }
    return encode_frame(MsgType::Stream, seq, w.span(), out);
}

std::size_t encode(const ErrorReply& m, std::uint16_t seq, FrameBuffer& out) {
    Writer w;
    w.u8(static_cast<std::uint8_t>(m.code));
    w.u8(m.request_type);
    return encode_frame(MsgType::Error, seq, w.span(), out);
}

// ---- parsing ----

namespace {

bool valid_date(std::uint32_t y, std::uint32_t m, std::uint32_t d) {
    static constexpr std::array<std::uint32_t, 12> kDays = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    if (y < 1900 || y > 9999 || m < 1 || m > 12 || d < 1 || d > kDays[m - 1]) return false;
    const bool leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
    return !(m == 2 && d == 29 && !leap);
}

}  // namespace

std::optional<std::uint32_t> parse_calibration_date(std::string_view t) {
    if (t.empty()) return 0u;
    if (t.size() != 10 || t[4] != '-' || t[7] != '-') return std::nullopt;
    std::uint32_t v[3] = {0, 0, 0};
    const std::size_t starts[3] = {0, 5, 8}, lens[3] = {4, 2, 2};
    for (int f = 0; f < 3; ++f) {
        for (std::size_t i = 0; i < lens[f]; ++i) {
            const char c = t[starts[f] + i];
            if (c < '0' || c > '9') return std::nullopt;
            v[f] = v[f] * 10 + static_cast<std::uint32_t>(c - '0');
        }
    }
    if (!valid_date(v[0], v[1], v[2])) return std::nullopt;
    return v[0] * 10000 + v[1] * 100 + v[2];
}

std::string format_calibration_date(std::uint32_t n) {
    if (n == 0 || !valid_date(n / 10000, n / 100 % 100, n % 100)) return {};
    char buf[16];
    std::snprintf(buf, sizeof buf, "%04u-%02u-%02u", n / 10000, n / 100 % 100, n % 100);
    return buf;
}

std::optional<IdentifyReply> parse_identify_reply(std::span<const std::uint8_t> body) {
    // 43 bytes: firmware before the calibration date; 47: with it. Longer: later fields, not read here.
    if (body.size() != 43 && body.size() < 47) return std::nullopt;
    Reader r{body};
    IdentifyReply m;
    m.protocol_version = r.u8();
    m.model = r.str(12);
    m.serial = r.str(12);
    m.firmware = r.str(8);
    m.calibrated_length_nm = r.u32();
    m.resolution_nm = r.u16();
    m.range_nm = r.u32();
    if (body.size() >= 47) m.calibration_date = r.u32();
    if (m.resolution_nm == 0 || m.calibrated_length_nm == 0) return std::nullopt;
    if (m.calibration_date != 0 && format_calibration_date(m.calibration_date).empty()) return std::nullopt;
    return m;
}

std::optional<StatusReply> parse_status_reply(std::span<const std::uint8_t> body) {
    if (body.size() != 12) return std::nullopt;
    Reader r{body};
    StatusReply m;
    m.battery_pct = r.u8();
    m.battery_mV = r.u16();
    m.bar_temp_cC = r.i16();
    m.error_flags = r.u16();
    m.streaming = r.u8() != 0;
    m.sample_rate_hz = r.u16();
    m.averaging = r.u8();
    m.referenced = r.u8() != 0;
    return m;
}

std::optional<ConfigureBody> parse_configure(std::span<const std::uint8_t> body) {
    if (body.size() != 3) return std::nullopt;
    Reader r{body};
    ConfigureBody m;
    m.sample_rate_hz = r.u16();
    m.averaging = r.u8();
    return m;
}

std::optional<std::uint32_t> parse_heartbeat(std::span<const std::uint8_t> body) {
    if (body.size() != 4) return std::nullopt;
    Reader r{body};
    return r.u32();
}

std::optional<HeartbeatReply> parse_heartbeat_reply(std::span<const std::uint8_t> body) {
    if (body.size() != 12) return std::nullopt;
    Reader r{body};
    HeartbeatReply m;
    m.token = r.u32();
    m.uptime_us = r.u64();
    return m;
}

std::optional<ErrorReply> parse_error(std::span<const std::uint8_t> body) {
    if (body.size() != 2) return std::nullopt;
    Reader r{body};
    ErrorReply m;
    m.code = static_cast<ErrorCode>(r.u8());
    m.request_type = r.u8();
    return m;
}

bool parse_stream(std::span<const std::uint8_t> body, StreamFrame& out) {
    if (body.size() < kStreamHeaderSize + 3) return false;
    const std::uint8_t* p = body.data();
    const std::size_t count = p[14];
    if (count == 0 || count > kMaxSamplesPerFrame || body.size() != kStreamHeaderSize + 3 * count) return false;
    std::uint64_t t0 = 0;
    for (int i = 7; i >= 0; --i) t0 = (t0 << 8) | p[i];
    out.t0_us = t0;
    out.period_ns =
        static_cast<std::uint32_t>(p[8] | (p[9] << 8) | (p[10] << 16)) | (static_cast<std::uint32_t>(p[11]) << 24);
    out.bar_temp_cC = static_cast<std::int16_t>(p[12] | (p[13] << 8));
    out.count = static_cast<std::uint8_t>(count);
    const std::uint8_t* s = p + kStreamHeaderSize;
    for (std::size_t i = 0; i < count; ++i, s += 3) {
        out.samples[i].displacement = static_cast<std::int16_t>(s[0] | (s[1] << 8));
        out.samples[i].flags = s[2];
    }
    return true;
}

// ---- decoder ----

void Decoder::reset() {
    pending_size_ = 0;
    overflow_ = false;
}

DecodeResult Decoder::finish(std::span<const std::uint8_t> encoded) {
    DecodeResult r;
    r.status = DecodeStatus::Invalid;
    const auto n = cobs_decode(encoded, decoded_);
    if (!n) {
        r.reason = InvalidReason::Cobs;
    } else if (*n < kHeaderSize + kCrcSize) {
        r.reason = InvalidReason::TooShort;
    } else {
        const std::size_t body_end = *n - kCrcSize;
        const auto want = static_cast<std::uint16_t>(decoded_[body_end] | (decoded_[body_end + 1] << 8));
        if (crc16({decoded_.data(), body_end}) != want) {
            r.reason = InvalidReason::Crc;
        } else {
            r.status = DecodeStatus::Frame;
            r.frame.version = decoded_[0];
            r.frame.type = static_cast<MsgType>(decoded_[1]);
            r.frame.seq = static_cast<std::uint16_t>(decoded_[2] | (decoded_[3] << 8));
            r.frame.body = {decoded_.data() + kHeaderSize, body_end - kHeaderSize};
            ++frames_;
            return r;
        }
    }
    ++invalid_;
    return r;
}

DecodeResult Decoder::next(std::span<const std::uint8_t>& input) {
    while (!input.empty()) {
        const void* hit = std::memchr(input.data(), 0, input.size());
        if (hit == nullptr) {
            // No delimiter: keep what fits, remember an overflow.
            const std::size_t room = kMaxEncodedSize - pending_size_;
            if (overflow_ || input.size() > room) {
                overflow_ = true;
                pending_size_ = 0;
            } else {
                std::memcpy(pending_.data() + pending_size_, input.data(), input.size());
                pending_size_ += input.size();
            }
            input = {};
            return {};
        }
        const auto len = static_cast<std::size_t>(static_cast<const std::uint8_t*>(hit) - input.data());
        const std::span<const std::uint8_t> chunk = input.first(len);
        input = input.subspan(len + 1);
        if (overflow_ || pending_size_ + len > kMaxEncodedSize) {
            reset();
            ++invalid_;
            return {DecodeStatus::Invalid, InvalidReason::TooLong, {}};
        }
        if (pending_size_ == 0) {
            if (len == 0) continue;  // empty frame / padding
            return finish(chunk);    // fast path: the whole frame is in `input`
        }
        if (len > 0) std::memcpy(pending_.data() + pending_size_, chunk.data(), len);
        const std::size_t total = pending_size_ + len;
        pending_size_ = 0;
        return finish({pending_.data(), total});
    }
    return {};
}

}  // namespace ballbar::device::protocol
