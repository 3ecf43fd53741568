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

nlohmann::ordered_json verdict_json(const acquisition::SsmVerdict& v) {
    if (!v.judged()) return nullptr;
    nlohmann::ordered_json checks = nlohmann::ordered_json::array();
    for (const acquisition::Check& c : v.checks) {
        const bool um = c.unit == "µm";
        // "|ΔV1|" → "dV1", "Δα" → "d_alpha": the vocabulary's ASCII names
        const std::string figure = c.figure == "|ΔV1|"   ? "dV1"
                                   : c.figure == "|ΔV2|" ? "dV2"
                                   : c.figure == "Δα"    ? "d_alpha"
                                   : c.figure == "Δβ"    ? "d_beta"
                                                         : "d_gamma";
        checks.push_back({{"test", c.test},
                          {"figure", figure},
                          {um ? "value_um" : "value_arcsec", c.value},
                          {um ? "tolerance_um" : "tolerance_arcsec", c.tolerance},
                          {"pass", c.pass()}});
    }
    return {{"pass", v.pass()}, {"summary", v.summary()}, {"checks", checks}};
}

}  // namespace ballbar::app
