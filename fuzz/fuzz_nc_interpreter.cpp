// SPDX-License-Identifier: MIT
// libFuzzer target: the NC interpreter and compensator that `ballbar compensate` runs on a user's
// program (analysis/src/nc_interpreter.cpp, nc_compensate.cpp): arcs, offsets, tool lengths, TCP mode
// switches, G93, G53. The first byte picks the options; a program is compensated through a small
// error model or refused with NcError, and every step's points are finite.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "ballbar/analysis/nc_compensate.hpp"
#include "ballbar/analysis/nc_interpreter.hpp"
#include "fuzz_check.hpp"

namespace ba = ballbar::analysis;
using ballbar::fuzz::check;

namespace {

bool finite(const ba::Pose& p) {
    return std::isfinite(p.X_mm) && std::isfinite(p.Y_mm) && std::isfinite(p.Z_mm) && std::isfinite(p.A_rad) &&
           std::isfinite(p.B_rad) && std::isfinite(p.C_rad);
}

ba::NcInterpreterOptions options(std::uint8_t bits) {
    ba::NcInterpreterOptions o;
    o.dialect = (bits & 1) ? ba::NcDialect::LinuxCNC : ba::NcDialect::Fanuc;
    o.second_rotary = (bits & 2) ? 'B' : 'C';
    if (bits & 4) {
        o.have_offsets = true;
        o.offsets.work["G54"] = ba::Pose{10, -5, 2, 0, 0, 0};
        o.offsets.work["G55"] = ba::Pose{-100, 50, 0, 0, 0, 0.1};
        o.offsets.tool_length_mm[1] = 50;
        o.offsets.tool_length_mm[2] = 120.5;
        o.offsets.measured_tool_length_mm = 50;
    }
    o.tcp = *ba::tcp_codes_for((bits & 8) ? "fanuc" : "linuxcnc");
    o.tcp_at_start = bits & 16;
    o.iso_directions = bits & 32;
    return o;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
    const ba::NcInterpreterOptions opt = options(data[0]);
    try {
        ba::NcInterpreter in(text, opt);
        ba::NcStep step;
        std::size_t points = 0;
        while (in.next(step) && points < 1'000'000) {
            check(finite(step.start), "the start of a step is finite");
            for (const auto& p : step.points) check(finite(p), "every point is finite");
            points += step.points.size();
        }
    } catch (const ba::NcError&) {
    }
    if (data[0] & 64) {
        ba::MachineGeometry g;
        g.type = ba::MachineType::TTTRR;
        g.c_offset_mm = {0, 0, -100};
        ba::ErrorParams e{};
        for (std::size_t i = 0; i < e.values.size(); ++i) e.values[i] = 1e-6 * static_cast<double>(i % 7);
        ba::NcCompensateOptions co;
        co.allow_truncated = data[0] & 128;
        co.exact = data[0] & 2;
        std::size_t out = 0;
        try {
            (void)ba::compensate_nc_program(text, g, e, opt, co, [&](std::string_view s) { out += s.size(); });
        } catch (const ba::NcError&) {
        }
    }
    return 0;
}
