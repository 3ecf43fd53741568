// SPDX-License-Identifier: MIT
// libFuzzer target: arbitrary bytes, fed to the decoder in pieces whose sizes come from the input
// itself. Checks that the decoder never reads or writes out of bounds, never returns a frame with a
// body over 56 bytes, consumes input monotonically, and that every frame it accepts re-encodes to
// bytes that decode to the same frame; and runs every body parser on every frame.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <span>

#include "ballbar/device/protocol.hpp"

using namespace ballbar::device::protocol;

namespace {

void check(bool ok) {
    if (!ok) std::abort();
}

void exercise_parsers(const FrameView& f) {
    StreamFrame s;
    if (parse_stream(f.body, s)) check(s.count >= 1 && s.count <= kMaxSamplesPerFrame);
    (void)parse_identify_reply(f.body);
    (void)parse_status_reply(f.body);
    (void)parse_configure(f.body);
    (void)parse_heartbeat(f.body);
    (void)parse_heartbeat_reply(f.body);
    (void)parse_error(f.body);
}

void round_trip(const FrameView& f) {
    FrameBuffer buf{};
    const std::size_t n = encode_frame(f.type, f.seq, f.body, buf, f.version);
    check(n <= kMaxFrameSize && buf[n - 1] == 0);
    for (std::size_t i = 0; i + 1 < n; ++i) check(buf[i] != 0);
    Decoder d;
    std::span<const std::uint8_t> in{buf.data(), n};
    const DecodeResult r = d.next(in);
    check(r.status == DecodeStatus::Frame && in.empty());
    check(r.frame.version == f.version && r.frame.type == f.type && r.frame.seq == f.seq);
    check(r.frame.body.size() == f.body.size() &&
          (f.body.empty() || std::memcmp(r.frame.body.data(), f.body.data(), f.body.size()) == 0));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    const std::size_t piece = 1 + data[0] % 97;  // 1..97 byte pieces
    std::span<const std::uint8_t> rest{data + 1, size - 1};
    Decoder d;
    while (!rest.empty()) {
        std::span<const std::uint8_t> in = rest.first(std::min(piece, rest.size()));
        rest = rest.subspan(in.size());
        while (true) {
            const std::size_t before = in.size();
            const DecodeResult r = d.next(in);
            check(in.size() <= before);
            if (r.status == DecodeStatus::NeedMore) {
                check(in.empty());
                break;
            }
            if (r.status == DecodeStatus::Frame) {
                check(r.frame.body.size() <= kMaxBodySize);
                // Copy out: the view is only valid until the decoder's next call.
                std::uint8_t body[kMaxBodySize];
                std::memcpy(body, r.frame.body.data(), r.frame.body.size());
                FrameView f = r.frame;
                f.body = {body, r.frame.body.size()};
                exercise_parsers(f);
                round_trip(f);
            } else {
                check(r.reason != InvalidReason::None);
            }
        }
    }
    // COBS on the raw input: decoding never overruns, and encoded output decodes back.
    std::uint8_t out[256];
    (void)cobs_decode({data, std::min<std::size_t>(size, 255)}, out);
    if (size <= 254) {
        std::uint8_t enc[256];
        const std::size_t n = cobs_encode({data, size}, enc);
        const auto m = cobs_decode({enc, n}, out);
        check(m && *m == size && std::memcmp(out, data, size) == 0);
    }
    return 0;
}
