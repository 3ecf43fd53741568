// SPDX-License-Identifier: MIT
// What the commands' --json outputs share, so each follows docs/cli.md's vocabulary the same way: a
// text that may be missing is null, a vector is [x, y, z], the orientation angles a test measures are
// flat keys with their unit (d_alpha_rad) and their uncertainty next to them (d_alpha_rad_std).
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "ballbar/acquisition/plan.hpp"
#include "ballbar/acquisition/verdict.hpp"
#include "ballbar/analysis/orientation.hpp"
#include "ballbar/analysis/types.hpp"

namespace ballbar::app {

/// The text, or null when it is empty (the vocabulary has no "").
inline nlohmann::ordered_json text_or_null(const std::string& s) {
    return s.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(s);
}

/// [x, y, z].
inline nlohmann::ordered_json vec3_json(const analysis::Vec3& v) {
    return nlohmann::ordered_json::array({v.x(), v.y(), v.z()});
}

/// The angles a test of `kind` measures on a machine of `type`, as `prefix` + "d_alpha_rad" + `suffix`
/// (and d_beta, d_gamma): only those the test observes, each null when `e` is empty (singular).
void put_angles(nlohmann::ordered_json& out, const std::string& prefix, const std::string& suffix,
                const std::optional<analysis::OrientationErrors>& e, analysis::MachineType type,
                acquisition::TestKind kind);

/// An SSM verdict (acquisition/verdict.hpp) as {"pass", "checks": [{"test", "figure", "value_um" or
/// "value_arcsec", "tolerance_um" or "tolerance_arcsec", "pass"}]}; null when nothing was judged.
nlohmann::ordered_json verdict_json(const acquisition::SsmVerdict& v);

}  // namespace ballbar::app
