// SPDX-License-Identifier: MIT
// libFuzzer target: the NC program reader (analysis/src/nc_program.cpp) in both dialects, whole
// (parse_nc_program) and streaming (NcReader), which must agree; an accepted program is written back
// and must read back with the same number of blocks.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string_view>

#include "ballbar/analysis/nc_program.hpp"
#include "fuzz_check.hpp"

namespace ba = ballbar::analysis;
using ballbar::fuzz::check;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    const ba::NcDialect dialect = (data[0] & 1) ? ba::NcDialect::LinuxCNC : ba::NcDialect::Fanuc;
    const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
    ba::NcProgram program;
    try {
        program = ba::parse_nc_program(text, dialect);
    } catch (const ba::NcError&) {
        return 0;
    }
    // The streaming reader gives the same blocks.
    ba::NcReader reader(text, dialect);
    ba::NcBlock block;
    std::size_t n = 0;
    while (reader.next(block)) {
        check(n < program.blocks.size(), "the reader gives no more blocks than the parser");
        check(block.line == program.blocks[n].line && block.motion == program.blocks[n].motion,
              "the reader and the parser agree");
        ++n;
    }
    check(n == program.blocks.size(), "the reader gives as many blocks as the parser");
    for (const auto& b : program.blocks) {
        for (const auto& v : {b.X_mm, b.Y_mm, b.Z_mm, b.A_rad, b.B_rad, b.C_rad, b.feed_mm_min})
            check(!v || std::isfinite(*v), "axis words and feeds are finite");
        check(std::isfinite(b.dwell_s) && b.dwell_s >= 0, "dwell finite and not negative");
    }
    std::string written;
    try {
        written = ba::write_nc_program(program);
    } catch (const ba::AnalysisError&) {
        return 0;  // a value that does not fit the word format is refused by the writer
    }
    ba::NcProgram back;
    try {
        back = ba::parse_nc_program(written, dialect);
    } catch (const ba::NcError& e) {
        std::fprintf(stderr, "written back: %s\n%s\n", e.what(), written.c_str());
        check(false, "an accepted program, written back, reads back");
    }
    std::size_t moves = 0, moves_back = 0;
    for (const auto& b : program.blocks) moves += b.motion != ba::NcMotion::None;
    for (const auto& b : back.blocks) moves_back += b.motion != ba::NcMotion::None;
    check(moves == moves_back, "the round trip keeps every motion block");
    return 0;
}
