// SPDX-License-Identifier: MIT
// libFuzzer target: the plan file of `measure` (ballbar-plan/1, acquisition/src/plan.cpp) for each
// machine type (first byte). Refused with PlanError only; an accepted plan is written back and must
// read back.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string_view>

#include "ballbar/acquisition/machine_file.hpp"
#include "ballbar/acquisition/plan.hpp"
#include "fuzz_check.hpp"

namespace acq = ballbar::acquisition;
namespace ba = ballbar::analysis;
using ballbar::fuzz::check;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    const ba::MachineType type = data[0] % 3 == 0   ? ba::MachineType::RRTTT
                                 : data[0] % 3 == 1 ? ba::MachineType::TTTRR
                                                    : ba::MachineType::RTTTR;
    const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
    acq::PlanSpec spec;
    try {
        spec = acq::parse_plan_file(text, type);
    } catch (const acq::PlanError&) {
        return 0;
    }
    try {
        const acq::PlanSpec back = acq::parse_plan_file(acq::write_plan_file(spec, type), type);
        check(back.tests.size() == spec.tests.size(), "the plan round trip keeps every test");
    } catch (const acq::PlanError& e) {
        std::fprintf(stderr, "written back: %s\n", e.what());
        check(false, "an accepted plan, written back, reads back");
    }
    return 0;
}
