// SPDX-License-Identifier: MIT
// libFuzzer target: the instrument protocol's body parsers past the CRC gate. The fuzzer's bytes are a
// message type and a body; the body is wrapped in a valid frame (COBS, CRC-16), decoded by the real
// Decoder and handed to the parser of its type (and to every other parser). Whatever a parser accepts
// must re-encode to a frame that parses back to the same values.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

#include "ballbar/device/protocol.hpp"
#include "fuzz_check.hpp"

using namespace ballbar::device::protocol;
using ballbar::fuzz::check;

namespace {

/// The body of the one frame in `wire` (as the host's decoder sees it).
std::span<const std::uint8_t> decode_one(const FrameBuffer& wire, std::size_t n, Decoder& d) {
    std::span<const std::uint8_t> in{wire.data(), n};
    const DecodeResult r = d.next(in);
    check(r.status == DecodeStatus::Frame, "an encoded frame decodes");
    return r.frame.body;
}

void stream(std::span<const std::uint8_t> body) {
    StreamFrame s;
    if (!parse_stream(body, s)) return;
    check(s.count >= 1 && s.count <= kMaxSamplesPerFrame, "stream count in range");
    FrameBuffer buf{};
    const std::size_t n = encode(s, 7, buf);
    Decoder d;
    StreamFrame back;
    check(parse_stream(decode_one(buf, n, d), back), "a re-encoded stream frame parses");
    check(back.count == s.count && back.t0_us == s.t0_us && back.period_ns == s.period_ns &&
              back.bar_temp_cC == s.bar_temp_cC,
          "stream frame round trip");
    for (std::size_t i = 0; i < s.count; ++i)
        check(back.samples[i].displacement == s.samples[i].displacement && back.samples[i].flags == s.samples[i].flags,
              "stream sample round trip");
}

template <class T, class Parse, class Encode>
void round_trip(std::span<const std::uint8_t> body, Parse parse, Encode enc) {
    const auto v = parse(body);
    if (!v) return;
    FrameBuffer buf{};
    const std::size_t n = enc(*v, buf);
    Decoder d;
    const auto back = parse(decode_one(buf, n, d));
    check(back.has_value(), "a re-encoded body parses");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 2) return 0;
    const auto type = static_cast<MsgType>(data[0]);
    const std::uint8_t version = (data[1] & 1) ? kVersion : data[1];
    std::span<const std::uint8_t> body{data + 2, std::min<std::size_t>(size - 2, kMaxBodySize)};

    // Through the real wire path: a valid frame around the body, decoded.
    FrameBuffer wire{};
    const std::size_t n = encode_frame(type, 1, body, wire, version);
    Decoder d;
    std::span<const std::uint8_t> in{wire.data(), n};
    const DecodeResult r = d.next(in);
    if (r.status != DecodeStatus::Frame) return 0;  // a version the decoder refuses
    check(r.frame.body.size() == body.size(), "the body survives framing");
    std::uint8_t copy[kMaxBodySize];
    std::memcpy(copy, r.frame.body.data(), r.frame.body.size());
    const std::span<const std::uint8_t> b{copy, r.frame.body.size()};

    stream(b);
    round_trip<IdentifyReply>(b, parse_identify_reply,
                              [](const IdentifyReply& m, FrameBuffer& o) { return encode(m, 2, o); });
    round_trip<StatusReply>(b, parse_status_reply,
                            [](const StatusReply& m, FrameBuffer& o) { return encode(m, 3, o); });
    round_trip<ConfigureBody>(
        b, parse_configure, [](const ConfigureBody& m, FrameBuffer& o) { return encode(m, MsgType::Configure, 4, o); });
    round_trip<HeartbeatReply>(b, parse_heartbeat_reply,
                               [](const HeartbeatReply& m, FrameBuffer& o) { return encode(m, 5, o); });
    round_trip<ErrorReply>(b, parse_error, [](const ErrorReply& m, FrameBuffer& o) { return encode(m, 6, o); });
    if (const auto token = parse_heartbeat(b)) {
        FrameBuffer buf{};
        const std::size_t m = encode_heartbeat(*token, 8, buf);
        Decoder d2;
        check(parse_heartbeat(decode_one(buf, m, d2)) == token, "heartbeat round trip");
    }
    return 0;
}
