// SPDX-License-Identifier: MIT
// Which serial gauge answers on a port the ball-bar protocol found silent (gauge.hpp, find_serial_gauge).
#include <exception>

#include "ballbar/device/gauge.hpp"

namespace ballbar::device::gauge {

std::optional<Kind> find_serial_gauge(const std::string& path, std::chrono::milliseconds per_protocol) {
    // Each one's request is harmless to the others (a request for a reading, a query, a register read).
    // The Digimatic adaptor first: it answers any character with a reading that a Sylvac's decoder would
    // take for its own; a Sylvac says nothing to the adaptor's "R" (no carriage return).
    for (const Kind kind : {Kind::Digimatic, Kind::Sylvac, Kind::Modbus}) {
        try {
            const std::unique_ptr<Gauge> g = open_gauge(std::string(to_string(kind)) + ":" + path);
            // Twice: the ball-bar's binary frames before it are the start of a line the first request ends
            // (a Sylvac takes "<frames>?" for an unknown command and says nothing, as a real one does).
            for (int attempt = 0; attempt < 2; ++attempt) {
                try {
                    (void)g->read(per_protocol);
                    return kind;
                } catch (const DeviceError& e) {
                    if (e.kind() == DeviceErrorKind::Disconnected) return std::nullopt;
                }
            }
        } catch (const std::exception&) {  // cannot be opened as this protocol's port: try the next
        }
    }
    return std::nullopt;
}

std::string serial_gauge_hint(std::string_view uri) {
    constexpr std::string_view kSerial = "serial:";
    if (!uri.starts_with(kSerial)) return {};
    std::string path(uri.substr(kSerial.size()));
    if (const auto q = path.find('?'); q != std::string::npos) path.resize(q);  // its line settings
    if (path.empty()) return {};
    const auto kind = find_serial_gauge(path, std::chrono::milliseconds(250));
    if (!kind) return {};
    const std::string scheme = to_string(*kind);
    return "; a " + scheme + " gauge answers on " + path + std::string(kUseDevice) + scheme + ":" + path;
}

std::optional<std::string> hinted_device(std::string_view message) {
    const auto at = message.find(kUseDevice);
    if (at == std::string_view::npos) return std::nullopt;
    std::string_view uri = message.substr(at + kUseDevice.size());
    uri = uri.substr(0, uri.find_first_of(" ;)"));  // the URI ends the hint; a message may go on after it
    if (uri.empty()) return std::nullopt;
    return std::string(uri);
}

}  // namespace ballbar::device::gauge
