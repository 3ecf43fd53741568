// SPDX-License-Identifier: MIT
#include "compensation_demo.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>

#include "figures.hpp"

namespace ballbar::app {

namespace ba = ballbar::analysis;

std::string compensation_demo_text(const workflow::CompensationDemo& demo, double noise_um) {
    std::ostringstream out;
    out << "Emulated TTTRR machine, seed-like errors (rotary block dominant)\n"
        << "Plan: " << demo.locations << " SSM locations, " << demo.readings << " readings, bar noise " << noise_um
        << " µm\n";
    for (const auto& s : demo.not_identifiable) out << "  not identifiable: " << s << '\n';
    out << "Identification: " << fit_report(demo.fit);
    out << "Identified vs true (identifiable: what this plan can see of the truth, EZZ held at 0;\n"
           "!! marks an estimate more than 5σ from it):\n";
    for (const auto& p : demo.identified) {
        const auto& e = p.estimate;
        const ScreenUnit u = screen_unit(ba::param_info(*e.param).unit);
        char line[240];
        std::snprintf(line, sizeof line, "  %-6s %26s  (true %s, identifiable %s)%s\n", e.name.c_str(),
                      with_uncertainty(e.estimate * u.factor, e.std * u.factor, u.symbol).c_str(),
                      with_uncertainty(p.true_value * u.factor, 0, u.symbol).c_str(),
                      with_uncertainty(p.identifiable_value * u.factor, 0, u.symbol).c_str(),
                      sigma_flag(e.estimate, e.std, p.identifiable_value, "the identifiable value").c_str());
        out << line;
    }
    out << "Test path: " << demo.path_blocks << " blocks, " << (demo.exact ? "exact" : "first-order")
        << " compensation\n";
    for (int a = 0; a < 3; ++a)
        out << "  "
            << "XYZ"[a] << ": RMS error " << demo.rms_before_um[a] << " µm → " << demo.rms_after_um[a]
            << " µm, improvement " << demo.improvement(a) << "x\n";
    return out.str();
}

nlohmann::ordered_json compensation_demo_json(const workflow::CompensationDemo& demo,
                                              const workflow::CompensationDemoOptions& options) {
    using ojson = nlohmann::ordered_json;
    // docs/cli.md's vocabulary: the unit in each key, an item's unit in `unit` where a list mixes them.
    const auto per_axis = [](auto value) { return ojson{{"X", value(0)}, {"Y", value(1)}, {"Z", value(2)}}; };
    ojson j;
    j["improvement_ratio"] = per_axis([&](int a) { return demo.improvement(a); });
    j["rms_before_um"] = per_axis([&](int a) { return demo.rms_before_um[a]; });
    j["rms_after_um"] = per_axis([&](int a) { return demo.rms_after_um[a]; });
    j["max_after_um"] = demo.max_after_um;
    j["identification_rms_um"] = demo.fit.residual_rms_mm * 1e3;
    j["identified"] = ojson::array();
    for (const auto& p : demo.identified) {
        const auto& e = p.estimate;
        const auto sigma = [&](double reference) {
            return e.std > 0 ? ojson(std::abs(e.estimate - reference) / e.std) : nullptr;
        };
        j["identified"].push_back({{"name", e.name},
                                   {"unit", std::string(ba::to_string(ba::param_info(*e.param).unit))},
                                   {"value", e.estimate},
                                   {"value_std", e.std},
                                   {"true_value", p.true_value},
                                   {"identifiable_value", p.identifiable_value},
                                   {"observable", e.observable},
                                   {"sigma_from_true", sigma(p.true_value)},
                                   // |estimate − identifiable| / std; over 5 the text output flags it
                                   {"sigma_from_identifiable", sigma(p.identifiable_value)}});
    }
    j["not_identifiable"] = demo.not_identifiable;
    j["readings"] = demo.readings;
    j["locations"] = demo.locations;
    j["converged"] = demo.fit.converged;
    j["method"] = demo.exact ? "exact" : "first-order";
    j["path_blocks"] = demo.path_blocks;
    j["singular_blocks"] = demo.singular_blocks;
    j["noise_um"] = options.noise_um;
    j["seed"] = options.seed;
    return j;
}

}  // namespace ballbar::app
