// SPDX-License-Identifier: MIT
// The error model as ballbar stores and exchanges it: `ballbar-model/1` (docs/identification.md,
// "The stored model"). One reader and one writer, used by every command, the report and any other
// front end: `identify` and `discover` write it, `compensate` (and a controller's module) read it.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/analysis/empirical.hpp"
#include "ballbar/analysis/error_params.hpp"
#include "ballbar/analysis/types.hpp"

namespace ballbar::storage {

inline constexpr std::string_view kModelFormat = "ballbar-model/1";

/// One parameter of the model with its value in the analysis' units (mm, rad, mm/mm, …).
struct ModelParam {
    analysis::Param param{};
    double value = 0;
    std::optional<double> std;  ///< its standard uncertainty, where the fit gave one
};

/// A socket's position as the fit found it (identify with free sockets).
struct ModelSocket {
    analysis::Vec3 nominal_mm = analysis::Vec3::Zero();
    analysis::Vec3 offset_mm = analysis::Vec3::Zero();
};

struct ErrorModel {
    analysis::MachineGeometry machine;
    std::vector<ModelParam> params;                ///< the parameters the model holds (others are 0)
    std::vector<analysis::Param> unobservable;     ///< named by the fit, held at 0
    std::vector<analysis::LearnedTerm> empirical;  ///< terms learned by `discover` (docs/discovery.md)
    std::vector<ModelSocket> sockets;
    std::optional<double> residual_rms_um;  ///< of the fit that made the model
    std::optional<int> readings;            ///< readings of that fit
    std::optional<bool> converged;
    std::string added;  ///< `discover`'s versions: the effect or family this version added
    /// The poses of the readings the model was fitted to ("measured_poses"): `compensate` says where a
    /// program leaves them. Empty for models written before it was kept.
    std::optional<analysis::PoseRange> measured_poses;

    /// The values as the kinematics take them (parameters the model does not hold are 0).
    analysis::ErrorParams values() const;
};

/// The model as a JSON object, "format" first; doubles round-trip exactly. "std", "unobservable" and
/// "sockets" are always written (empty when the model has none).
std::string model_to_json(const ErrorModel& model);

/// Reads a model strictly: unknown keys, unknown parameters or terms, values that are not finite or
/// outside the parameter's physical limits are refused with FormatError naming the key. "format" may
/// be absent (models stored before it was written), otherwise it must be ballbar-model/1.
ErrorModel model_from_json(std::string_view json);

}  // namespace ballbar::storage
