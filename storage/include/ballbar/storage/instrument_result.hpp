// SPDX-License-Identifier: MIT
// The stored result of kind "instrument": a digital gauge's identity and what the session measured of it
// (docs/instruments.md). Written by workflow's GaugeSource, read by `sessions show` and any front end.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

namespace ballbar::storage {

inline constexpr std::string_view kInstrumentResultKind = "instrument";

struct GaugeInstrumentRecord {
    std::string kind, maker, model;  ///< empty when the gauge was never identified
    std::optional<std::string> serial, firmware;
    bool inch = false, low_battery = false;
    std::string uri;
    double resolution_mm = 0, reading_rate_hz = 0;  ///< as measured over the session
    double target_rate_hz = 0, calibrated_length_mm = 0;
    int sign = 1;  ///< −1: the gauge sits reversed on the bar
    std::uint64_t readings = 0, not_ready = 0, out_of_range = 0, timeouts = 0, invalid = 0, errors = 0;
};

std::string gauge_instrument_to_json(const GaugeInstrumentRecord& record);

/// Strict: a missing or mistyped figure, or an unknown key, is FormatError naming it.
GaugeInstrumentRecord gauge_instrument_from_json(std::string_view text);

}  // namespace ballbar::storage
