// SPDX-License-Identifier: MIT
// The gauge cables' USB IDs and the udev rules made from them.
#include <array>

#include "ballbar/device/gauge.hpp"
#include "ballbar/device/ids.hpp"

namespace ballbar::device {
namespace {

constexpr std::array<GaugeUsbId, 1> kGaugeIds{{
    {gauge::kItnVendorId, gauge::kItnProductId, "mitutoyo-itn", "usb", "Mitutoyo USB-ITN"},
}};

}  // namespace

std::span<const GaugeUsbId> gauge_usb_ids() {
    return kGaugeIds;
}

std::optional<GaugeUsbId> find_gauge_usb_id(std::uint16_t vid, std::uint16_t pid) {
    for (const auto& id : kGaugeIds)
        if (id.vid == vid && id.pid == pid) return id;
    return std::nullopt;
}

std::string gauge_udev_rules(bool plugdev) {
    std::string s =
        "# udev rules for the digital gauges ballbar drives (docs/instruments.md). GENERATED from the gauge ID\n"
        "# table (device/src/gauges/gauge_ids.cpp) by `ballbar udev-rules" +
        std::string(plugdev ? " --plugdev" : "") + "`: do not edit; tests/device_usb checks that the two agree.\n";
    s += plugdev ? "# Access for the members of the plugdev group (mode 0660); nothing is world-writable.\n"
                 : "# Access for the user at the seat (logind's uaccess tag, applied by 73-seat-late.rules).\n";
    for (const GaugeUsbId& id : kGaugeIds) {
        s += "\n# " + hex4(id.vid) + ":" + hex4(id.pid) + " " + id.model + " (" + id.scheme + ": URIs)\n";
        const std::string match = std::string(id.subsystem) == "usb"
                                      ? "SUBSYSTEM==\"usb\", ENV{DEVTYPE}==\"usb_device\", ATTR{idVendor}==\"" +
                                            hex4(id.vid) + "\", ATTR{idProduct}==\"" + hex4(id.pid) + "\""
                                      : "SUBSYSTEM==\"tty\", ATTRS{idVendor}==\"" + hex4(id.vid) +
                                            "\", ATTRS{idProduct}==\"" + hex4(id.pid) + "\"";
        s += match + (plugdev ? ", MODE=\"0660\", GROUP=\"plugdev\"\n" : ", TAG+=\"uaccess\"\n");
    }
    return s;
}

}  // namespace ballbar::device
