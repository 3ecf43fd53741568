// SPDX-License-Identifier: MIT
// `ballbar devices [--json]`: the instruments attached over USB CDC serial, USB bulk and HID.
#include <iostream>
#include <nlohmann/json.hpp>

#include "ballbar/device/enumerate.hpp"
#include "command.hpp"
#include "json_out.hpp"

namespace {

nlohmann::ordered_json to_json(const ballbar::device::FoundInstrument& f) {
    using ballbar::app::text_or_null;
    return {{"link", ballbar::device::to_string(f.link)},
            {"model", text_or_null(f.model)},
            {"serial", text_or_null(f.serial)},
            {"path", f.path},
            {"uri", f.uri},
            {"vid", ballbar::device::hex4(f.vid)},
            {"pid", ballbar::device::hex4(f.pid)},
            {"note", text_or_null(f.note)}};
}

}  // namespace

BALLBAR_COMMAND(devices) {
    auto* sub = root.add_subcommand("devices", "List attached ball-bar instruments (serial, USB, HID)");
    auto json = std::make_shared<bool>(false);
    sub->add_flag("--json", *json, "Print a JSON array instead of a table");
    sub->callback([&globals, json] {
        globals.action = [json]() -> int {
            const auto found = ballbar::device::enumerate_instruments();
            for (const auto& w : found.warnings) std::cerr << "ballbar: warning: " << w << '\n';
            if (*json) {
                nlohmann::ordered_json arr = nlohmann::ordered_json::array();
                for (const auto& f : found.instruments) arr.push_back(to_json(f));
                std::cout << arr.dump(2) << '\n';
                return ballbar::app::kExitOk;
            }
            if (found.instruments.empty()) {
                std::cout << "no instruments found (links searched: serial, usb, hid)\n";
                return ballbar::app::kExitOk;
            }
            for (const auto& f : found.instruments) {
                std::cout << ballbar::device::to_string(f.link) << "  " << f.model << "  serial "
                          << (f.serial.empty() ? "?" : f.serial) << "  " << f.path << "  " << f.uri;
                if (!f.note.empty()) std::cout << "  (" << f.note << ")";
                std::cout << '\n';
            }
            return ballbar::app::kExitOk;
        };
    });
}
