// SPDX-License-Identifier: MIT
// The library of named physical effects the discovery workflow can add to a machine model.
//
// Each effect is one physical term with one parameter of the shared error-parameter table
// (error_params.hpp), an ISO 230 symbol where one exists, a unit, and the variable its signature
// follows in the readings (time, bar temperature, an axis position, ...). docs/discovery.md lists them.
#pragma once

#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "ballbar/analysis/error_params.hpp"
#include "ballbar/analysis/types.hpp"

namespace ballbar::analysis {

/// The variables residuals are analysed against (one reading each), and that an effect follows.
enum class ExplainingVariable {
    time,           ///< session time, s
    bar_temp,       ///< bar temperature, °C
    X,              ///< commanded X, mm
    Y,              ///< commanded Y, mm
    Z,              ///< commanded Z, mm
    rotary_first,   ///< the type's first rotary axis (A), rad
    rotary_second,  ///< the type's second rotary axis (B or C), rad
    bar_direction,  ///< a constant error vector seen through the bar's direction (and a constant offset)
    kCount
};
constexpr std::size_t kExplainingVariableCount = static_cast<std::size_t>(ExplainingVariable::kCount);

/// Operator-facing name: "time", "bar_temperature", "X", "Y", "Z", "A", "B"/"C", "bar_direction".
std::string_view to_string(ExplainingVariable v, MachineType type);

/// One named effect. `param` is the error parameter it adds to the model.
struct Effect {
    std::string_view id;   ///< e.g. "scale_X"
    std::string_view iso;  ///< ISO 230 symbol ("EXX"), empty where none exists
    Param param;
    ExplainingVariable variable;  ///< what its signature follows
    std::string_view description;

    ParamUnit unit() const { return param_info(param).unit; }
};

/// Every effect, in a fixed order (the order ties are broken in).
std::span<const Effect> effect_library();
const Effect* find_effect(std::string_view id);
/// The effect that adds `p` (every parameter of the table has exactly one).
const Effect& effect_for(Param p);

/// The effects that can change a reading on a machine of this type and whose parameter is not in
/// `model`: the candidates discovery tests.
std::vector<const Effect*> candidate_effects(MachineType type, std::span<const Param> model);

/// Parses a model description: comma-separated parameter names (`Y0A,Z0A`) or effect ids
/// (`scale_X`), or `base` (the type's rotary location errors and zero offsets), or a mix.
/// Throws AnalysisError naming the unknown entry.
std::vector<Param> parse_model(std::string_view text, MachineType type);

}  // namespace ballbar::analysis
