// SPDX-License-Identifier: MIT
#include "json_out.hpp"

#include "ballbar/acquisition/plan.hpp"

namespace ballbar::app {

void put_angles(nlohmann::ordered_json& out, const std::string& prefix, const std::string& suffix,
                const std::optional<analysis::OrientationErrors>& e, analysis::MachineType type,
                acquisition::TestKind kind) {
    const analysis::MeasuredAngles angles = acquisition::measured_angles(type, kind);
    const auto put = [&](bool measured, const char* name, double v) {
        if (measured) out[prefix + name + "_rad" + suffix] = e ? nlohmann::ordered_json(v) : nullptr;
    };
    put(angles.alpha, "d_alpha", e ? e->d_alpha_rad : 0);
    put(angles.beta, "d_beta", e ? e->d_beta_rad : 0);
    put(angles.gamma, "d_gamma", e ? e->d_gamma_rad : 0);
}

}  // namespace ballbar::app
