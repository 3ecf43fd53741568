// SPDX-License-Identifier: MIT
#pragma once

#include <chrono>
#include <cstdint>
#include <vector>

#include "ballbar/device/transport.hpp"

namespace ballbar::device::testing {

/// Reads until `n` bytes arrived or `limit` passed; returns what arrived.
inline std::vector<std::uint8_t> read_bytes(Transport& t, std::size_t n, std::chrono::milliseconds limit) {
    std::vector<std::uint8_t> got;
    const auto deadline = std::chrono::steady_clock::now() + limit;
    std::uint8_t buf[256];
    while (got.size() < n && std::chrono::steady_clock::now() < deadline) {
        const std::size_t k = t.read(buf, std::chrono::milliseconds(50));
        got.insert(got.end(), buf, buf + k);
    }
    return got;
}

/// A pattern that contains every byte value (0x00 included, as in COBS delimiters).
inline std::vector<std::uint8_t> pattern(std::size_t n, std::uint8_t seed = 0) {
    std::vector<std::uint8_t> v(n);
    for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<std::uint8_t>(i * 7 + seed);
    return v;
}

}  // namespace ballbar::device::testing
