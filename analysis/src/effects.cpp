// SPDX-License-Identifier: MIT
#include "ballbar/analysis/effects.hpp"

#include <algorithm>
#include <array>
#include <string>

namespace ballbar::analysis {
namespace {

using enum Param;
using V = ExplainingVariable;

constexpr std::array<Effect, kParamCount> kEffects{{
    {"bar_length_offset", "", bar_length, V::bar_direction, "the bar's calibrated length is off: every reading shifts"},
    {"bar_thermal_expansion", "", bar_kappa, V::bar_temp, "the bar grows with its temperature: L*kappa*(T_bar - 20 C)"},
    {"spindle_thermal_growth", "", spindle_growth, V::time, "the tool ball drifts along Z in proportion to time"},
    {"scale_X", "EXX", EXX, V::X, "X positioning error proportional to the X position"},
    {"scale_Y", "EYY", EYY, V::Y, "Y positioning error proportional to the Y position"},
    {"scale_Z", "EZZ", EZZ, V::Z, "Z positioning error proportional to the Z position"},
    {"squareness_XY", "C0Y", C0Y, V::Y, "out-of-squareness of Y to X"},
    {"squareness_YZ", "A0Z", A0Z, V::Z, "out-of-squareness of Z to Y"},
    {"squareness_ZX", "B0Z", B0Z, V::Z, "out-of-squareness of Z to X"},
    {"tool_length_offset", "", tool_length, V::bar_direction, "the tool ball sits off its place along the spindle"},
    {"location_Y0A", "Y0A", Y0A, V::rotary_first, "A axis line: position error in Y"},
    {"location_Z0A", "Z0A", Z0A, V::rotary_first, "A axis line: position error in Z"},
    {"location_B0A", "B0A", B0A, V::rotary_first, "A axis: tilt about Y"},
    {"location_C0A", "C0A", C0A, V::rotary_first, "A axis: tilt about Z"},
    {"zero_offset_A", "", A_zero, V::rotary_first, "A axis: zero-angle offset"},
    {"location_X0B", "X0B", X0B, V::rotary_second, "B axis line: position error in X"},
    {"location_Z0B", "Z0B", Z0B, V::rotary_second, "B axis line: position error in Z"},
    {"location_A0B", "A0B", A0B, V::rotary_second, "B axis: tilt about X"},
    {"location_C0B", "C0B", C0B, V::rotary_second, "B axis: tilt about Z"},
    {"zero_offset_B", "", B_zero, V::rotary_second, "B axis: zero-angle offset"},
    {"location_X0C", "X0C", X0C, V::rotary_second, "C axis line: position error in X"},
    {"location_Y0C", "Y0C", Y0C, V::rotary_second, "C axis line: position error in Y"},
    {"location_A0C", "A0C", A0C, V::rotary_second, "C axis: tilt about X"},
    {"location_B0C", "B0C", B0C, V::rotary_second, "C axis: tilt about Y"},
    {"zero_offset_C", "", C_zero, V::rotary_second, "C axis: zero-angle offset"},
}};

static_assert(
    [] {
        std::array<int, kParamCount> seen{};
        for (const auto& e : kEffects) ++seen[static_cast<std::size_t>(e.param)];
        return std::all_of(seen.begin(), seen.end(), [](int n) { return n == 1; });
    }(),
    "every parameter has exactly one effect");

std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
    return s;
}

}  // namespace

std::string_view to_string(ExplainingVariable v, MachineType type) {
    switch (v) {
        case V::time:
            return "time";
        case V::bar_temp:
            return "bar_temperature";
        case V::X:
            return "X";
        case V::Y:
            return "Y";
        case V::Z:
            return "Z";
        case V::rotary_first:
            return "A";
        case V::rotary_second:
            return rotary_axes(type).second == 'C' ? "C" : "B";
        case V::bar_direction:
            return "bar_direction";
        case V::kCount:
            break;
    }
    return "?";
}

std::span<const Effect> effect_library() {
    return kEffects;
}

const Effect* find_effect(std::string_view id) {
    for (const auto& e : kEffects)
        if (e.id == id) return &e;
    return nullptr;
}

const Effect& effect_for(Param p) {
    for (const auto& e : kEffects)
        if (e.param == p) return e;
    throw AnalysisError("no effect for parameter " + std::string(param_info(p).name));
}

std::vector<const Effect*> candidate_effects(MachineType type, std::span<const Param> model) {
    const std::vector<Param> relevant = params_for(type);
    std::vector<const Effect*> out;
    for (const auto& e : kEffects) {
        if (std::find(relevant.begin(), relevant.end(), e.param) == relevant.end()) continue;
        if (std::find(model.begin(), model.end(), e.param) != model.end()) continue;
        out.push_back(&e);
    }
    return out;
}

std::vector<Param> parse_model(std::string_view text, MachineType type) {
    std::vector<Param> out;
    auto add = [&out](Param p) {
        if (std::find(out.begin(), out.end(), p) == out.end()) out.push_back(p);
    };
    const std::vector<Param> relevant = params_for(type);
    while (!text.empty()) {
        const std::size_t comma = text.find(',');
        const std::string_view item = trim(text.substr(0, comma));
        text = comma == std::string_view::npos ? std::string_view{} : text.substr(comma + 1);
        if (item.empty()) continue;
        if (item == "base") {
            for (Param p : rotary_params_for(type)) add(p);
            continue;
        }
        std::optional<Param> p = parse_param(item);
        if (!p)
            if (const Effect* e = find_effect(item)) p = e->param;
        if (!p) throw AnalysisError("unknown model parameter or effect '" + std::string(item) + "'");
        if (std::find(relevant.begin(), relevant.end(), *p) == relevant.end())
            throw AnalysisError("parameter '" + std::string(item) + "' has no effect on a " +
                                std::string(to_string(type)) + " machine");
        add(*p);
    }
    return out;
}

}  // namespace ballbar::analysis
