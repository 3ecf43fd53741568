// SPDX-License-Identifier: MIT
#include "ballbar/analysis/error_params.hpp"

#include <algorithm>

namespace ballbar::analysis {
namespace {

using enum Param;
using enum ParamUnit;

constexpr std::array<ParamInfo, kParamCount> kParams{{
    {Y0A, "Y0A", mm, "A axis line: position error in Y"},
    {Z0A, "Z0A", mm, "A axis line: position error in Z"},
    {B0A, "B0A", rad, "A axis: tilt about Y (squareness of A to Z)"},
    {C0A, "C0A", rad, "A axis: tilt about Z (squareness of A to Y)"},
    {A_zero, "A_zero", rad, "A axis: zero-angle offset"},
    {X0B, "X0B", mm, "B axis line: position error in X"},
    {Z0B, "Z0B", mm, "B axis line: position error in Z"},
    {A0B, "A0B", rad, "B axis: tilt about X"},
    {C0B, "C0B", rad, "B axis: tilt about Z"},
    {B_zero, "B_zero", rad, "B axis: zero-angle offset"},
    {X0C, "X0C", mm, "C axis line: position error in X"},
    {Y0C, "Y0C", mm, "C axis line: position error in Y"},
    {A0C, "A0C", rad, "C axis: tilt about X (squareness of C to Y)"},
    {B0C, "B0C", rad, "C axis: tilt about Y (squareness of C to X)"},
    {C_zero, "C_zero", rad, "C axis: zero-angle offset"},
    {EXX, "EXX", mm_per_mm, "X axis scale: positioning error proportional to X"},
    {EYY, "EYY", mm_per_mm, "Y axis scale: positioning error proportional to Y"},
    {EZZ, "EZZ", mm_per_mm, "Z axis scale: positioning error proportional to Z"},
    {C0Y, "C0Y", rad, "squareness of Y to X"},
    {B0Z, "B0Z", rad, "squareness of Z to X"},
    {A0Z, "A0Z", rad, "squareness of Z to Y"},
    {tool_length, "tool_length", mm, "tool ball off its nominal place along the spindle axis"},
    {spindle_growth, "spindle_growth", mm_per_h, "tool ball drift along machine Z with session time"},
    {bar_length, "bar_length", mm, "bar calibrated-length error: every reading shifts by it"},
    {bar_kappa, "bar_kappa", per_K, "bar thermal expansion: reading grows by L*kappa*(T_bar - 20 C)"},
}};

static_assert(
    [] {
        for (std::size_t i = 0; i < kParams.size(); ++i)
            if (static_cast<std::size_t>(kParams[i].id) != i) return false;
        return true;
    }(),
    "kParams must be in the order of enum Param");

}  // namespace

std::span<const ParamInfo> all_params() {
    return kParams;
}

const ParamInfo& param_info(Param p) {
    return kParams[static_cast<std::size_t>(p)];
}

std::optional<Param> parse_param(std::string_view name) {
    for (const auto& info : kParams)
        if (info.name == name) return info.id;
    return std::nullopt;
}

std::string_view to_string(ParamUnit unit) {
    switch (unit) {
        case mm:
            return "mm";
        case rad:
            return "rad";
        case mm_per_mm:
            return "mm_per_mm";
        case mm_per_h:
            return "mm_per_h";
        case per_K:
            return "per_K";
    }
    return "?";
}

std::vector<Param> rotary_params_for(MachineType type) {
    switch (type) {
        case MachineType::RRTTT:
            return {Y0A, Z0A, B0A, C0A, X0B, Z0B, A0B, C0B, A_zero, B_zero};
        case MachineType::TTTRR:
            return {Y0A, Z0A, B0A, C0A, X0C, Y0C, A0C, B0C, A_zero, C_zero};
        case MachineType::RTTTR:
            return {X0B, Z0B, A0B, C0B, Y0A, Z0A, B0A, C0A, B_zero, A_zero};
    }
    return {};
}

std::vector<Param> params_for(MachineType type) {
    std::vector<Param> out = rotary_params_for(type);
    for (Param p : {EXX, EYY, EZZ, C0Y, B0Z, A0Z, tool_length, spindle_growth, bar_length, bar_kappa}) out.push_back(p);
    return out;
}

}  // namespace ballbar::analysis
