// SPDX-License-Identifier: MIT
// The machine's error parameters: one fixed table, shared by the actual kinematics, the emulator's
// simulated machine, identification and the discovery workflow.
//
// Naming follows ISO 230-1/230-7 where a symbol exists (location errors `Y0A`, `X0C`, squareness
// `C0Y`, scale `EXX`); zero-angle offsets of the rotary axes are `A_zero`, `B_zero`, `C_zero`.
// The sign conventions are those of docs/kinematics.md.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "ballbar/analysis/types.hpp"

namespace ballbar::analysis {

enum class Param : int {
    // A axis (about X): position of the axis line in Y and Z, tilt about Y and Z, zero offset.
    Y0A,
    Z0A,
    B0A,
    C0A,
    A_zero,
    // B axis (about Y).
    X0B,
    Z0B,
    A0B,
    C0B,
    B_zero,
    // C axis (about Z).
    X0C,
    Y0C,
    A0C,
    B0C,
    C_zero,
    // Linear axes: scale (linear positioning error, mm/mm) and squareness (rad).
    EXX,
    EYY,
    EZZ,
    C0Y,
    B0Z,
    A0Z,
    // Spindle and tool.
    tool_length,     ///< tool ball off its nominal place along the spindle axis, mm
    spindle_growth,  ///< tool ball drift along machine +Z, mm per hour of session time
    // The bar itself.
    bar_length,  ///< reading offset: the bar's calibrated length is off, mm
    bar_kappa,   ///< apparent thermal expansion of the bar, 1/K (reading grows by L·κ·(T − 20 °C))
    kCount
};

constexpr std::size_t kParamCount = static_cast<std::size_t>(Param::kCount);

enum class ParamUnit { mm, rad, mm_per_mm, mm_per_h, per_K };

struct ParamInfo {
    Param id;
    std::string_view name;  ///< ISO symbol or our name, e.g. "X0C", "A_zero", "EXX"
    ParamUnit unit;
    std::string_view description;
};

std::span<const ParamInfo> all_params();
const ParamInfo& param_info(Param p);
std::optional<Param> parse_param(std::string_view name);
std::string_view to_string(ParamUnit unit);

/// The parameters that can have an effect on a machine of this type (the others never change a
/// reading: the C axis of an RRTTT, say).
std::vector<Param> params_for(MachineType type);

/// Location errors and zero offsets of the type's rotary axes: the base model of identification and
/// discovery (for TTTRR: Y0A Z0A B0A C0A X0C Y0C A0C B0C A_zero C_zero).
std::vector<Param> rotary_params_for(MachineType type);

/// Values of every parameter; zero means the nominal machine.
template <typename T>
struct ErrorParamsT {
    std::array<T, kParamCount> values{};

    T& operator[](Param p) { return values[static_cast<std::size_t>(p)]; }
    const T& operator[](Param p) const { return values[static_cast<std::size_t>(p)]; }
};
using ErrorParams = ErrorParamsT<double>;

}  // namespace ballbar::analysis
