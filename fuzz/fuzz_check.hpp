// SPDX-License-Identifier: MIT
// What the fuzz targets share: a check that stops the fuzzer (a finding) when a property fails.
#pragma once

#include <cstdio>
#include <cstdlib>

namespace ballbar::fuzz {

inline void check(bool ok, const char* what) {
    if (!ok) {
        std::fprintf(stderr, "fuzz property failed: %s\n", what);
        std::abort();
    }
}

}  // namespace ballbar::fuzz
