// SPDX-License-Identifier: MIT
// Internal: the wide strings hidapi reports (manufacturer, product, serial) as printable ASCII.
#pragma once

#include <string>

namespace ballbar::device::detail {

/// Printable ASCII kept, anything else shown as '?'; a null pointer gives "".
inline std::string narrow(const wchar_t* w) {
    std::string s;
    if (!w) return s;
    for (; *w; ++w) s.push_back(*w >= 0x20 && *w < 0x7f ? static_cast<char>(*w) : '?');
    return s;
}

}  // namespace ballbar::device::detail
