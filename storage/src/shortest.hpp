// SPDX-License-Identifier: MIT
// The text the storage formats write numbers in (readings and trace files): the shortest decimal that
// reads back to the same double.
#pragma once

#include <charconv>
#include <string>

namespace ballbar::storage::detail {

inline std::string shortest(double v) {
    char buf[64];
    const auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, v);
    return ec == std::errc() ? std::string(buf, ptr) : std::to_string(v);
}

}  // namespace ballbar::storage::detail
