// SPDX-License-Identifier: MIT
#include "line_link.hpp"

#include <cmath>

namespace ballbar::device::gauge {

namespace detail {

Decoded take_line(std::string_view rx, char terminator) {
    Decoded d;
    const auto end = rx.find(terminator);
    if (end == std::string_view::npos) {
        if (rx.size() > kMaxLine) {
            d.result = Decode::Invalid;
            d.consumed = rx.size();
        }
        return d;
    }
    d.consumed = end + 1;
    d.text = std::string(rx.substr(0, end));
    if (terminator == '\n' && !d.text.empty() && d.text.back() == '\r') d.text.pop_back();
    d.result = Decode::Valid;
    if (d.text.size() > kMaxLine) d.result = Decode::Invalid;
    for (const char c : d.text) {
        if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) d.result = Decode::Invalid;
    }
    return d;
}

Decoded ask(Transport& link, std::string& rx, std::string_view command, Codec codec,
            std::chrono::milliseconds timeout) {
    using clock = std::chrono::steady_clock;
    // What is left is the rest of a reply we gave up on (cut off, or late): never the answer to this one.
    std::array<std::uint8_t, 256> buf{};
    while (link.read(buf, std::chrono::milliseconds(0)) > 0) {
    }
    rx.clear();
    link.write({reinterpret_cast<const std::uint8_t*>(command.data()), command.size()}, timeout);
    const auto deadline = clock::now() + timeout;
    for (;;) {
        const Decoded d = codec(rx);
        if (d.result == Decode::Valid) {
            rx.erase(0, d.consumed);
            return d;
        }
        if (d.result == Decode::Invalid) {
            const std::string bad = rx.substr(0, d.consumed);
            rx.erase(0, d.consumed);
            throw DeviceError(DeviceErrorKind::Protocol, link.uri() + ": reply outside the protocol: '" + bad + "'");
        }
        const auto now = clock::now();
        if (now >= deadline) {
            throw DeviceError(DeviceErrorKind::Timeout,
                              link.uri() + (rx.empty() ? ": no reply" : ": reply cut off ('" + rx + "')"));
        }
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now);
        const std::size_t n = link.read(buf, std::max(left, std::chrono::milliseconds(1)));
        rx.append(reinterpret_cast<const char*>(buf.data()), n);
    }
}

}  // namespace detail

const char* to_string(Kind kind) {
    switch (kind) {
        case Kind::Sylvac:
            return "sylvac";
        case Kind::MitutoyoItn:
            return "mitutoyo-itn";
        case Kind::Digimatic:
            return "digimatic";
        case Kind::Modbus:
            return "modbus";
    }
    return "?";
}

std::optional<Kind> parse_kind(std::string_view name) {
    for (Kind k : {Kind::Sylvac, Kind::MitutoyoItn, Kind::Digimatic, Kind::Modbus}) {
        if (name == to_string(k)) return k;
    }
    return std::nullopt;
}

const char* to_string(ReadingStatus s) {
    switch (s) {
        case ReadingStatus::Ok:
            return "ok";
        case ReadingStatus::NotReady:
            return "not ready";
        case ReadingStatus::OutOfRange:
            return "out of range";
        case ReadingStatus::Error:
            return "error";
    }
    return "?";
}

double Reading::resolution_mm() const {
    const double step = std::pow(10.0, -decimals);
    return inch ? step * 25.4 : step;
}

std::optional<Reading> parse_decimal(std::string_view t) {
    Reading r;
    std::size_t i = 0;
    bool negative = false;
    if (i < t.size() && (t[i] == '+' || t[i] == '-')) negative = t[i++] == '-';
    // Leading blanks after the sign are allowed (some gauges pad: "+  0.123").
    while (i < t.size() && t[i] == ' ') ++i;
    int digits = 0;
    bool point = false;
    double v = 0;
    for (; i < t.size(); ++i) {
        const char c = t[i];
        if (c == '.' && !point) {
            point = true;
        } else if (c >= '0' && c <= '9') {
            v = v * 10 + (c - '0');
            ++digits;
            if (point) ++r.decimals;
        } else {
            return std::nullopt;
        }
    }
    if (digits == 0 || digits > 12) return std::nullopt;
    r.value = (negative ? -v : v) / std::pow(10.0, r.decimals);
    return r;
}

}  // namespace ballbar::device::gauge
