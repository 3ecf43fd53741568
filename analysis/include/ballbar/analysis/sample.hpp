// SPDX-License-Identifier: MIT
// One raw sample of the bar, as the instrument reports it. Shared by device (which decodes it),
// acquisition (which captures points from a stream of them) and storage (which keeps every one).
#pragma once

#include <cstdint>

#include "ballbar/analysis/rounding.hpp"

namespace ballbar::analysis {

/// Flags of a sample (bit values are the protocol's, docs/protocol.md).
enum SampleFlags : std::uint16_t {
    kSampleOutOfRange = 1u << 0,     ///< the transducer is beyond its ±1 mm range; the value is clamped
    kSampleNotReferenced = 1u << 1,  ///< no reference (zero) has been set since power-on
    kSampleTempInvalid = 1u << 2,    ///< no bar temperature: the sensor failed, or there is none (a gauge)
    /// Host-only (never sent by the instrument): the first sample after frames were lost. The driver
    /// sets it so a consumer never averages across a gap without knowing.
    kSampleAfterGap = 1u << 8,
};

struct BarSample {
    std::uint64_t seq = 0;             ///< host-side sample sequence number, contiguous from 0 in a session
    std::uint64_t device_time_us = 0;  ///< instrument clock
    std::int32_t displacement_nm = 0;  ///< transducer displacement from the calibrated length
    std::uint16_t flags = 0;
    float bar_temp_C = 20.0f;

    /// The bar temperature as stored and sent: whole milli-kelvin (20.3, not the float's 20.299999237060547).
    double temperature_C() const { return decimal_round(static_cast<double>(bar_temp_C), 3); }

    /// Bar length (ball centre to ball centre) for a bar calibrated at `calibrated_length_mm`.
    double length_mm(double calibrated_length_mm) const { return calibrated_length_mm + displacement_nm * 1e-6; }
};

}  // namespace ballbar::analysis
