// SPDX-License-Identifier: MIT
#include "ballbar/analysis/types.hpp"

namespace ballbar::analysis {

std::string_view to_string(MachineType type) {
    switch (type) {
        case MachineType::RRTTT:
            return "RRTTT";
        case MachineType::TTTRR:
            return "TTTRR";
        case MachineType::RTTTR:
            return "RTTTR";
    }
    return "?";
}

std::optional<MachineType> parse_machine_type(std::string_view text) {
    if (text == "RRTTT") return MachineType::RRTTT;
    if (text == "TTTRR") return MachineType::TTTRR;
    if (text == "RTTTR") return MachineType::RTTTR;
    return std::nullopt;
}

RotaryAxes rotary_axes(MachineType type) {
    switch (type) {
        case MachineType::RRTTT:
            return {'A', 'B'};
        case MachineType::TTTRR:
            return {'A', 'C'};
        case MachineType::RTTTR:
            return {'A', 'B'};
    }
    return {'A', 'B'};
}

}  // namespace ballbar::analysis
