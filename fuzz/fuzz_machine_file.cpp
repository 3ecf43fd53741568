// SPDX-License-Identifier: MIT
// libFuzzer target: the JSON machine inputs — the machine file of `measure` (ballbar-machine/1,
// acquisition/src/machine_file.cpp), the `machine` object of readings headers, models and exports
// (storage/src/machine_json.cpp), and the instrument object. Refused with their error types only; an
// accepted machine file is written back and must read back to the same geometry.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string_view>

#include "ballbar/acquisition/machine_file.hpp"
#include "ballbar/storage/machine_json.hpp"
#include "fuzz_check.hpp"

namespace acq = ballbar::acquisition;
namespace bs = ballbar::storage;
using ballbar::fuzz::check;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    try {
        std::vector<std::string> warnings;
        (void)bs::machine_from_json(text, &warnings);
    } catch (const bs::FormatError&) {
    }
    try {
        (void)bs::instrument_from_json(text);
    } catch (const bs::FormatError&) {
    }
    acq::MachineFile m;
    try {
        m = acq::parse_machine_file(text);
    } catch (const acq::PlanError&) {
        return 0;
    }
    acq::MachineFile back;
    try {
        back = acq::parse_machine_file(acq::write_machine_file(m));
    } catch (const acq::PlanError& e) {
        std::fprintf(stderr, "written back: %s\n", e.what());
        check(false, "an accepted machine file, written back, reads back");
    }
    check(back.geometry.type == m.geometry.type && back.geometry.tool_ball_mm == m.geometry.tool_ball_mm &&
              back.geometry.a_pivot_mm == m.geometry.a_pivot_mm && back.geometry.c_offset_mm == m.geometry.c_offset_mm,
          "the machine file round trip keeps the geometry");
    return 0;
}
