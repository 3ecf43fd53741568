// SPDX-License-Identifier: MIT
#include "ballbar/device/uri.hpp"

#include <charconv>
#include <stdexcept>

#include "ballbar/device/emulator.hpp"
#include "ballbar/device/hid.hpp"
#include "ballbar/device/pipe.hpp"
#include "ballbar/device/serial.hpp"
#include "ballbar/device/tcp.hpp"
#include "ballbar/device/usb.hpp"

namespace ballbar::device {

namespace {

constexpr const char* kDeviceUriForms =
    "expected a ball-bar as emulator:[CONFIG], serial:PATH, tcp:HOST:PORT, usb:VID:PID[:SERIAL] or "
    "hid:VID:PID[:SERIAL], or a digital gauge as sylvac:PATH, mitutoyo-itn:[SERIAL], digimatic:PATH or "
    "modbus:PATH[?slave=N&baud=B]";

[[noreturn]] void bad(std::string_view uri, const std::string& why) {
    throw std::invalid_argument("bad device URI '" + std::string(uri) + "': " + why + " (" + kDeviceUriForms + ")");
}

std::uint16_t parse_hex16(std::string_view uri, std::string_view s, const char* what) {
    unsigned v = 0;
    const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v, 16);
    if (s.empty() || s.size() > 4 || ec != std::errc() || p != s.data() + s.size()) {
        bad(uri, std::string(what) + " must be 1-4 hex digits, not '" + std::string(s) + "'");
    }
    return static_cast<std::uint16_t>(v);
}

}  // namespace

DeviceUri parse_device_uri(std::string_view uri) {
    const auto colon = uri.find(':');
    if (colon == std::string_view::npos) bad(uri, "no scheme");
    const std::string_view scheme = uri.substr(0, colon);
    const std::string_view rest = uri.substr(colon + 1);
    DeviceUri d;
    if (scheme == "emulator") {
        d.scheme = DeviceUri::Scheme::Emulator;
        d.path = rest;
    } else if (scheme == "serial") {
        d.scheme = DeviceUri::Scheme::Serial;
        if (rest.empty()) bad(uri, "missing the port path");
        d.path = rest;
    } else if (scheme == "tcp") {
        d.scheme = DeviceUri::Scheme::Tcp;
        const auto c = rest.rfind(':');
        if (c == std::string_view::npos || c == 0) bad(uri, "missing HOST:PORT");
        d.host = rest.substr(0, c);
        if (d.host.size() > 2 && d.host.front() == '[' && d.host.back() == ']')
            d.host = d.host.substr(1, d.host.size() - 2);
        const std::string_view ps = rest.substr(c + 1);
        unsigned port = 0;
        const auto [p, ec] = std::from_chars(ps.data(), ps.data() + ps.size(), port);
        if (ps.empty() || ec != std::errc() || p != ps.data() + ps.size() || port == 0 || port > 65535) {
            bad(uri, "port must be 1-65535");
        }
        d.port = static_cast<std::uint16_t>(port);
    } else if (scheme == "usb" || scheme == "hid") {
        d.scheme = scheme == "usb" ? DeviceUri::Scheme::Usb : DeviceUri::Scheme::Hid;
        const auto c1 = rest.find(':');
        if (c1 == std::string_view::npos) bad(uri, "missing VID:PID");
        const auto c2 = rest.find(':', c1 + 1);
        d.vid = parse_hex16(uri, rest.substr(0, c1), "VID");
        d.pid = parse_hex16(
            uri, rest.substr(c1 + 1, c2 == std::string_view::npos ? std::string_view::npos : c2 - c1 - 1), "PID");
        if (c2 != std::string_view::npos) d.serial = rest.substr(c2 + 1);
    } else {
        bad(uri, "unknown scheme '" + std::string(scheme) + "'");
    }
    return d;
}

std::unique_ptr<Transport> open_transport(std::string_view uri) {
    const DeviceUri d = parse_device_uri(uri);
    switch (d.scheme) {
        case DeviceUri::Scheme::Emulator: {
            EmulatorConfig cfg = d.path.empty() ? EmulatorConfig{} : load_emulator_config(d.path);
            const Pacing pacing = cfg.simulated_time ? Pacing::Simulated : Pacing::RealTime;
            return std::make_unique<PipeTransport>(std::make_unique<Emulator>(std::move(cfg)), pacing,
                                                   std::string(uri));
        }
        case DeviceUri::Scheme::Serial:
            return open_serial_transport(d.path);
        case DeviceUri::Scheme::Tcp:
            return open_tcp_transport(d.host, d.port);
        case DeviceUri::Scheme::Usb:
            return open_usb_transport(d.vid, d.pid, d.serial);
        case DeviceUri::Scheme::Hid:
            return open_hid_transport(d.vid, d.pid, d.serial);
    }
    throw std::invalid_argument("unreachable");
}

}  // namespace ballbar::device
