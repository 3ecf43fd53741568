// SPDX-License-Identifier: MIT
// libFuzzer target: the circular-test trace parser (`ballbar import` of a ballbar-trace/1 file,
// storage/src/trace_file.cpp). Accepted whole or refused with TraceFileError; an accepted trace is
// written back by format_trace and must read back with the same samples.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string_view>

#include "ballbar/analysis/circular.hpp"
#include "ballbar/storage/trace_file.hpp"
#include "fuzz_check.hpp"

namespace bs = ballbar::storage;
using ballbar::fuzz::check;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    (void)bs::looks_like_trace(text);
    bs::TraceFile trace;
    try {
        trace = bs::parse_trace(text);
    } catch (const bs::TraceFileError&) {
        return 0;
    }
    bs::TraceFile back;
    try {
        back = bs::parse_trace(bs::format_trace(trace));
    } catch (const bs::TraceFileError& e) {
        std::fprintf(stderr, "written back: %s\n", e.what());
        check(false, "an accepted trace, written back, reads back");
    }
    check(back.samples.size() == trace.samples.size(), "the round trip keeps every sample");
    return 0;
}
