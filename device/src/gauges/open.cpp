// SPDX-License-Identifier: MIT
// Gauge URIs: sylvac:PATH, mitutoyo-itn:[SERIAL], digimatic:PATH, modbus:PATH[?slave=N&baud=B].
#include <charconv>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "ballbar/device/gauge.hpp"
#include "ballbar/device/serial.hpp"

namespace ballbar::device::gauge {
namespace {

constexpr const char* kGaugeUriForms =
    "expected sylvac:PATH, mitutoyo-itn:[SERIAL], digimatic:PATH or modbus:PATH[?slave=N&baud=B]";

[[noreturn]] void bad(std::string_view uri, const std::string& why) {
    throw std::invalid_argument("bad device URI '" + std::string(uri) + "': " + why + " (" + kGaugeUriForms + ")");
}

int parse_int(std::string_view uri, std::string_view s, const char* what, int lo, int hi) {
    int v = 0;
    const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (s.empty() || ec != std::errc() || p != s.data() + s.size() || v < lo || v > hi)
        bad(uri, std::string(what) + " must be " + std::to_string(lo) + "-" + std::to_string(hi) + ", not '" +
                     std::string(s) + "'");
    return v;
}

}  // namespace

bool is_gauge_uri(std::string_view uri) {
    const auto colon = uri.find(':');
    return colon != std::string_view::npos && parse_kind(uri.substr(0, colon)).has_value();
}

Kind uri_kind(std::string_view uri) {
    const auto colon = uri.find(':');
    const auto k = colon == std::string_view::npos ? std::nullopt : parse_kind(uri.substr(0, colon));
    if (!k) bad(uri, "not a gauge scheme");
    return *k;
}

namespace {

struct UriParts {
    std::string_view target;  ///< path or serial
    int slave = 1, baud = 38400;
    bool inch = false;
    std::optional<double> sign, rate_hz;
};

UriParts split(std::string_view uri) {
    const Kind kind = uri_kind(uri);
    UriParts u;
    std::string_view rest = uri.substr(uri.find(':') + 1);
    if (const auto q = rest.find('?'); q != std::string_view::npos) {
        std::string_view params = rest.substr(q + 1);
        rest = rest.substr(0, q);
        while (!params.empty()) {
            const auto amp = params.find('&');
            const std::string_view kv = params.substr(0, amp);
            params = amp == std::string_view::npos ? std::string_view() : params.substr(amp + 1);
            const auto eq = kv.find('=');
            const std::string_view key = kv.substr(0, eq);
            const std::string_view value = eq == std::string_view::npos ? std::string_view() : kv.substr(eq + 1);
            if (key == "slave" && kind == Kind::Modbus) {
                u.slave = parse_int(uri, value, "slave", 1, 247);
            } else if (key == "baud" && kind == Kind::Modbus) {
                u.baud = parse_int(uri, value, "baud", 1200, 921600);
            } else if (key == "sign") {
                if (value != "1" && value != "+1" && value != "-1") bad(uri, "sign must be 1 or -1");
                u.sign = value == "-1" ? -1.0 : 1.0;
            } else if (key == "rate") {
                u.rate_hz = parse_int(uri, value, "rate", 1, 1000);
            } else if (key == "unit" && kind == Kind::MitutoyoItn) {
                if (value != "mm" && value != "inch") bad(uri, "unit must be mm or inch");
                u.inch = value == "inch";
            } else {
                bad(uri, "unknown parameter '" + std::string(key) + "' (" +
                             (kind == Kind::Modbus        ? "slave, baud, "
                              : kind == Kind::MitutoyoItn ? "unit, "
                                                          : "") +
                             "sign, rate)");
            }
        }
        rest = rest.substr(0, q);
    }
    u.target = rest;
    if (kind != Kind::MitutoyoItn && rest.empty()) bad(uri, "missing the port path");
    return u;
}

}  // namespace

BarOnGauge bar_from_uri(std::string_view uri, BarOnGauge bar) {
    const UriParts u = split(uri);
    if (u.sign) bar.sign = *u.sign;
    if (u.rate_hz) bar.target_rate_hz = *u.rate_hz;
    return bar;
}

std::unique_ptr<Gauge> open_gauge(std::string_view uri) {
    const Kind kind = uri_kind(uri);
    const UriParts u = split(uri);
    const std::string path(u.target);
    switch (kind) {
        case Kind::Sylvac:
            return make_sylvac_gauge(open_serial_transport(path, SerialFormat{4800, 7, 'E', 2}));
        case Kind::Digimatic:
            return make_digimatic_gauge(open_serial_transport(path, SerialFormat{9600, 8, 'N', 1}));
        case Kind::Modbus:
            return open_modbus_gauge(path, u.slave, u.baud);
        case Kind::MitutoyoItn:
            return make_itn_gauge(open_itn_usb(path), u.inch);
    }
    bad(uri, "unreachable");
}

std::int32_t to_nm(double mm) {
    const double nm = std::round(mm * 1e6);
    if (nm > 2.1e9) return 2'100'000'000;
    if (nm < -2.1e9) return -2'100'000'000;
    return static_cast<std::int32_t>(nm);
}

double max_feed_for_rate(double rate_hz, double radius_mm, double min_samples_per_deg) {
    if (!(rate_hz > 0) || !(radius_mm > 0) || !(min_samples_per_deg > 0)) return 0;
    // One degree of arc is 2πr/360 mm; at feed F mm/min it lasts (2πr/360)/(F/60) s and gets rate × that
    // readings: F ≤ rate × 60 × 2πr / (360 × min).
    return rate_hz * 60.0 * 2.0 * M_PI * radius_mm / (360.0 * min_samples_per_deg);
}

}  // namespace ballbar::device::gauge
