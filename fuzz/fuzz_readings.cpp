// SPDX-License-Identifier: MIT
// libFuzzer target: the readings file parser (`ballbar import`, storage/src/readings_file.cpp). A file
// is accepted whole or refused with ReadingsFileError; what it accepts is written back by
// format_readings and must read back with the same number of readings (the import/export round trip).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string_view>

#include "ballbar/storage/readings_file.hpp"
#include "fuzz_check.hpp"

namespace bs = ballbar::storage;
using ballbar::fuzz::check;

namespace {
bool finite(const ballbar::analysis::Pose& p) {
    return std::isfinite(p.X_mm) && std::isfinite(p.Y_mm) && std::isfinite(p.Z_mm) && std::isfinite(p.A_rad) &&
           std::isfinite(p.B_rad) && std::isfinite(p.C_rad);
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    bs::ReadingsFile file;
    try {
        file = bs::parse_readings(text);
    } catch (const bs::ReadingsFileError&) {
        return 0;
    }
    check(file.nominal_mm.size() == file.set.readings.size(), "a nominal length per reading");
    for (const auto& r : file.set.readings) {
        if (!std::isfinite(r.measured_mm) || !std::isfinite(r.time_s) || !finite(r.pose) || !r.socket_mm.allFinite())
            return 0;  // refused elsewhere (validation); the round trip is for finite files
    }
    bs::ReadingsFile back;
    try {
        back = bs::parse_readings(bs::format_readings(file.set, file.metadata));
    } catch (const bs::ReadingsFileError& e) {
        std::fprintf(stderr, "written back: %s\n", e.what());
        check(false, "an accepted file, written back, reads back");
    }
    check(back.set.readings.size() == file.set.readings.size(), "the round trip keeps every reading");
    return 0;
}
