// SPDX-License-Identifier: MIT
// libFuzzer target: the digital gauges' reply codecs (docs/instruments.md) on arbitrary bytes, as a
// driver feeds them: the receive buffer grows piece by piece (sizes from the input) and every Valid or
// Invalid answer drops what it consumed. Properties: NeedMore consumes nothing, Valid and Invalid
// consume at least one byte and never more than the buffer, readings are finite with 0..12 decimals;
// the SPC frame decoder on 13 nibbles.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "ballbar/device/gauge.hpp"
#include "fuzz_check.hpp"

namespace gg = ballbar::device::gauge;
using ballbar::fuzz::check;

namespace {

void check_reading(const gg::Decoded& d) {
    if (d.reading.status != gg::ReadingStatus::Ok) return;
    check(std::isfinite(d.reading.value), "a reading is finite");
    check(d.reading.decimals >= 0 && d.reading.decimals <= 12, "decimals 0..12");
    check(std::isfinite(d.reading.resolution_mm()) && d.reading.resolution_mm() > 0, "resolution positive");
}

void feed(gg::Decoded (*codec)(std::string_view), std::string_view bytes, std::size_t piece) {
    std::string rx;
    std::size_t pos = 0;
    for (int guard = 0; guard < 100000; ++guard) {
        const gg::Decoded d = codec(rx);
        if (d.result == gg::Decode::NeedMore) {
            check(d.consumed == 0, "NeedMore consumes nothing");
            if (pos >= bytes.size()) return;
            const std::size_t n = std::min(piece, bytes.size() - pos);
            rx.append(bytes.substr(pos, n));
            pos += n;
            continue;
        }
        check(d.consumed >= 1 && d.consumed <= rx.size(), "an answer consumes 1..size bytes");
        if (d.result == gg::Decode::Valid) check_reading(d);
        rx.erase(0, d.consumed);
    }
    check(false, "the codec made no progress");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    const std::size_t piece = 1 + data[0] % 50;
    const std::string_view bytes(reinterpret_cast<const char*>(data + 1), size - 1);
    feed(gg::decode_sylvac, bytes, piece);
    feed(gg::decode_itn, bytes, piece);
    feed(gg::decode_digimatic_line, bytes, piece);
    if (const auto r = gg::parse_decimal(bytes)) {
        check(std::isfinite(r->value) && r->decimals >= 0 && r->decimals <= 12,
              "parse_decimal: finite, 0..12 decimals");
    }
    if (size - 1 >= 13) {
        std::uint8_t nibbles[13];
        for (int i = 0; i < 13; ++i) nibbles[i] = static_cast<std::uint8_t>(data[1 + i] & 0x0f);
        const gg::Decoded d = gg::decode_spc_frame({nibbles, 13});
        if (d.result == gg::Decode::Valid) check_reading(d);
        (void)gg::decode_spc_frame({data + 1, 13});  // nibbles out of range too
    }
    if (size >= 5) {
        const auto hi = static_cast<std::uint16_t>(data[1] << 8 | data[2]);
        const auto lo = static_cast<std::uint16_t>(data[3] << 8 | data[4]);
        const gg::Reading r = gg::modbus_reading(hi, lo);
        check(std::isfinite(r.value) && std::abs(r.value) <= 214748.3648, "Modbus reading in the int32 range");
    }
    return 0;
}
