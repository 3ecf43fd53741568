// SPDX-License-Identifier: MIT
// The instrument protocol, version 1 (docs/protocol.md): COBS-framed, typed frames with a sequence
// number and a CRC-16/CCITT-FALSE. Everything here is pure: bytes in, frames out, no I/O, and nothing
// allocates (fixed-size buffers), so the decoder can run in the sample hot path and under a fuzzer.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace ballbar::device::protocol {

constexpr std::uint8_t kVersion = 1;
constexpr std::size_t kHeaderSize = 4;  ///< version, type, seq
constexpr std::size_t kCrcSize = 2;
constexpr std::size_t kMaxBodySize = 56;
constexpr std::size_t kMaxPayloadSize = kHeaderSize + kMaxBodySize + kCrcSize;  ///< 62
constexpr std::size_t kMaxEncodedSize = kMaxPayloadSize + 1;                    ///< COBS adds one byte
constexpr std::size_t kMaxFrameSize = kMaxEncodedSize + 1;  ///< with the 0x00 delimiter: 64, one HID report
constexpr std::size_t kMaxSamplesPerFrame = 13;
constexpr std::size_t kStreamHeaderSize = 15;
constexpr std::uint16_t kMinSampleRateHz = 1;
constexpr std::uint16_t kMaxSampleRateHz = 5000;
constexpr std::uint8_t kMaxAveraging = 64;
constexpr std::int16_t kDisplacementLimit = 10000;  ///< ±1 mm in 0.1 µm steps
constexpr std::uint32_t kResolutionNm = 100;

enum class MsgType : std::uint8_t {
    Identify = 0x01,
    Status = 0x02,
    Configure = 0x03,
    Start = 0x04,
    Stop = 0x05,
    SetReference = 0x06,
    Heartbeat = 0x07,
    IdentifyReply = 0x81,
    StatusReply = 0x82,
    ConfigureReply = 0x83,
    StartReply = 0x84,
    StopReply = 0x85,
    SetReferenceReply = 0x86,
    HeartbeatReply = 0x87,
    Stream = 0x10,
    Error = 0x7F,
};
std::string_view to_string(MsgType type);
constexpr MsgType reply_type(MsgType request) {
    return static_cast<MsgType>(static_cast<std::uint8_t>(request) | 0x80u);
}

enum class ErrorCode : std::uint8_t {
    UnknownType = 1,
    BadLength = 2,
    OutOfRange = 3,
    Busy = 4,
    UnsupportedVersion = 5,
    HardwareFault = 6,
};
std::string_view to_string(ErrorCode code);

/// Status error flags (u16).
enum StatusFlags : std::uint16_t {
    kStatusLowBattery = 1u << 0,
    kStatusTempSensorFault = 1u << 1,
    kStatusTransducerFault = 1u << 2,
    kStatusOverrun = 1u << 3,
};

/// CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF): check value 0x29B1 for "123456789".
std::uint16_t crc16(std::span<const std::uint8_t> data, std::uint16_t crc = 0xFFFF);

/// A decoded frame. `body` points into the decoder's buffer: valid until its next call.
struct FrameView {
    std::uint8_t version = kVersion;
    MsgType type = MsgType::Identify;
    std::uint16_t seq = 0;
    std::span<const std::uint8_t> body;
};

// ---- message bodies ----

struct IdentifyReply {
    std::uint8_t protocol_version = kVersion;
    std::string model;     ///< ≤ 12 characters
    std::string serial;    ///< ≤ 12 characters
    std::string firmware;  ///< ≤ 8 characters
    std::uint32_t calibrated_length_nm = 0;
    std::uint16_t resolution_nm = kResolutionNm;
    std::uint32_t range_nm = 1'000'000;
    /// Date of the bar's length calibration as the decimal number YYYYMMDD (20260115); 0 = unknown.
    /// Sent after range_nm (47-byte body); a 43-byte reply (firmware before it) parses with 0.
    std::uint32_t calibration_date = 0;
};

/// "2026-01-15" ⇄ 20260115. nullopt / "" for a text or number that is not a calendar date (0 ⇄ "").
std::optional<std::uint32_t> parse_calibration_date(std::string_view iso_date);
std::string format_calibration_date(std::uint32_t yyyymmdd);

struct StatusReply {
    std::uint8_t battery_pct = 100;
    std::uint16_t battery_mV = 4100;
    std::int16_t bar_temp_cC = 2000;
    std::uint16_t error_flags = 0;
    bool streaming = false;
    std::uint16_t sample_rate_hz = 1000;
    std::uint8_t averaging = 1;
    bool referenced = false;
};

struct ConfigureBody {  ///< Configure and ConfigureReply
    std::uint16_t sample_rate_hz = 1000;
    std::uint8_t averaging = 1;
};

struct HeartbeatReply {
    std::uint32_t token = 0;
    std::uint64_t uptime_us = 0;
};

struct StreamSample {
    std::int16_t displacement = 0;  ///< 0.1 µm steps
    std::uint8_t flags = 0;         ///< analysis::SampleFlags bits
};

struct StreamFrame {
    std::uint64_t t0_us = 0;
    std::uint32_t period_ns = 1'000'000;
    std::int16_t bar_temp_cC = 2000;
    std::uint8_t count = 0;
    std::array<StreamSample, kMaxSamplesPerFrame> samples{};
};

struct ErrorReply {
    ErrorCode code = ErrorCode::UnknownType;
    std::uint8_t request_type = 0;
};

// ---- encoding: each writes one complete wire frame (COBS + 0x00) into `out`, returns its size ----

using FrameBuffer = std::array<std::uint8_t, kMaxFrameSize>;

/// Any frame; `body.size()` must be ≤ kMaxBodySize (else std::length_error).
std::size_t encode_frame(MsgType type, std::uint16_t seq, std::span<const std::uint8_t> body, FrameBuffer& out,
                         std::uint8_t version = kVersion);
std::size_t encode_empty(MsgType type, std::uint16_t seq, FrameBuffer& out);
std::size_t encode(const IdentifyReply& m, std::uint16_t seq, FrameBuffer& out);
std::size_t encode(const StatusReply& m, std::uint16_t seq, FrameBuffer& out);
std::size_t encode(const ConfigureBody& m, MsgType type, std::uint16_t seq, FrameBuffer& out);
std::size_t encode_heartbeat(std::uint32_t token, std::uint16_t seq, FrameBuffer& out);
std::size_t encode(const HeartbeatReply& m, std::uint16_t seq, FrameBuffer& out);
std::size_t encode(const StreamFrame& m, std::uint16_t seq, FrameBuffer& out);
std::size_t encode(const ErrorReply& m, std::uint16_t seq, FrameBuffer& out);

// ---- body parsing: nullopt / false when the body has the wrong size or impossible values ----

std::optional<IdentifyReply> parse_identify_reply(std::span<const std::uint8_t> body);
std::optional<StatusReply> parse_status_reply(std::span<const std::uint8_t> body);
std::optional<ConfigureBody> parse_configure(std::span<const std::uint8_t> body);
std::optional<std::uint32_t> parse_heartbeat(std::span<const std::uint8_t> body);
std::optional<HeartbeatReply> parse_heartbeat_reply(std::span<const std::uint8_t> body);
std::optional<ErrorReply> parse_error(std::span<const std::uint8_t> body);
/// Hot path: fills `out` in place (no allocation).
bool parse_stream(std::span<const std::uint8_t> body, StreamFrame& out);

// ---- COBS ----

/// Encodes `in` (≤ 254 bytes) into `out` (≥ in.size() + 1), without delimiter; returns the size.
std::size_t cobs_encode(std::span<const std::uint8_t> in, std::span<std::uint8_t> out);
/// Decodes `in` (no delimiter) into `out`; nullopt if malformed (a 0x00 inside, a code past the end,
/// output too small).
std::optional<std::size_t> cobs_decode(std::span<const std::uint8_t> in, std::span<std::uint8_t> out);

// ---- decoding ----

enum class DecodeStatus { Frame, NeedMore, Invalid };
enum class InvalidReason { None, TooLong, Cobs, TooShort, Crc };
std::string_view to_string(InvalidReason reason);

struct DecodeResult {
    DecodeStatus status = DecodeStatus::NeedMore;
    InvalidReason reason = InvalidReason::None;
    FrameView frame;  ///< when status == Frame
};

/// Incremental frame decoder. Feed it any pieces of the byte stream; it returns one frame (or one
/// rejected frame) at a time and resynchronises at the next 0x00 after garbage. Frames of any version
/// and type are returned as long as COBS and CRC are sound: the caller checks version and type.
class Decoder {
  public:
    /// Consumes bytes from the front of `input` (advancing it) up to and including the end of the next
    /// frame. NeedMore: all of `input` was consumed and no frame is complete yet.
    DecodeResult next(std::span<const std::uint8_t>& input);
    /// Forgets a partial frame (after a reconnect).
    void reset();

    std::uint64_t frames() const { return frames_; }
    std::uint64_t invalid() const { return invalid_; }

  private:
    DecodeResult finish(std::span<const std::uint8_t> encoded);

    std::array<std::uint8_t, kMaxEncodedSize> pending_{};
    std::size_t pending_size_ = 0;
    bool overflow_ = false;
    std::array<std::uint8_t, kMaxEncodedSize> decoded_{};
    std::uint64_t frames_ = 0;
    std::uint64_t invalid_ = 0;
};

}  // namespace ballbar::device::protocol
