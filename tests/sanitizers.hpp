// SPDX-License-Identifier: MIT
// Whether the tests run under AddressSanitizer (the `asan` preset): some do less work there (ASan is
// ~10× slower, and reserves terabytes of address space, so no ulimit -v).
#pragma once

namespace ballbar::test {

#if defined(__SANITIZE_ADDRESS__)  // GCC
inline constexpr bool kSanitized = true;
#elif defined(__has_feature)  // clang
#if __has_feature(address_sanitizer)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
#else
inline constexpr bool kSanitized = false;
#endif

}  // namespace ballbar::test
