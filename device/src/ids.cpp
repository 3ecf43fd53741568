// SPDX-License-Identifier: MIT
#include "ballbar/device/ids.hpp"

#include <array>
#include <cstdio>

namespace ballbar::device {
namespace {

constexpr std::array<UsbId, 3> kIds{{
    {kBallbarVendorId, kBallbarBulkProductId, UsbLink::UsbBulk, "BallBar BB-1"},
    {kBallbarVendorId, kBallbarHidProductId, UsbLink::Hid, "BallBar BB-1H"},
    {kBallbarVendorId, kBallbarSerialProductId, UsbLink::Serial, "BallBar BB-1S"},
}};

}  // namespace

const char* to_string(UsbLink link) {
    switch (link) {
        case UsbLink::Serial:
            return "serial";
        case UsbLink::UsbBulk:
            return "usb";
        case UsbLink::Hid:
            return "hid";
    }
    return "?";
}

std::span<const UsbId> usb_ids() {
    return kIds;
}

std::optional<UsbId> find_usb_id(std::uint16_t vid, std::uint16_t pid) {
    for (const auto& id : kIds) {
        if (id.vid == vid && id.pid == pid) return id;
    }
    return std::nullopt;
}

UsbId usb_id_for(UsbLink link) {
    for (const auto& id : kIds) {
        if (id.link == link) return id;
    }
    return kIds.front();  // unreachable: the table has one entry per link
}

std::string hex4(std::uint16_t value) {
    char buf[8];
    std::snprintf(buf, sizeof buf, "%04x", static_cast<unsigned>(value));
    return buf;
}

}  // namespace ballbar::device
