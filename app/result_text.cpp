// SPDX-License-Identifier: MIT
// What `sessions show` says of each stored result: its values, with units and uncertainties
// (figures.hpp). The procedure's results are read by their codec (acquisition/result_codec.hpp), the
// identification by its (storage/identification_codec.hpp), the others as app/ stores them (cmd_discover.cpp,
// cmd_demo.cpp, gauge_source.cpp); anything else shows its numbers by name.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "ballbar/acquisition/result_codec.hpp"
#include "ballbar/analysis/error_params.hpp"
#include "ballbar/analysis/orientation.hpp"
#include "ballbar/storage/compensation_codec.hpp"
#include "ballbar/storage/discovery_codec.hpp"
#include "ballbar/storage/identification_codec.hpp"
#include "ballbar/storage/instrument_result.hpp"
#include "ballbar/storage/machine_json.hpp"
#include "figures.hpp"

namespace ballbar::app {
namespace {

namespace acq = ballbar::acquisition;
namespace ba = ballbar::analysis;
using nlohmann::json;

std::vector<std::string> ssm_lines(std::string_view payload) {
    const acq::LocationResult r = acq::location_from_json(payload);
    char buf[96];
    // ΔV as `measure` and `demo` print it, with its uncertainty (that of e, of which it is ±).
    std::string line = "test " + std::to_string(r.test + 1) + " step " + std::to_string(r.step) + ": ΔV " +
                       vec_um(r.dV_mm, &r.ssm.std_mm) + ", e " + vec_um(r.ssm.exact_mm, nullptr);
    std::snprintf(buf, sizeof buf, ", condition %.3g, %zu points", r.ssm.condition_number, r.ssm.n);
    return {line + buf};
}

std::vector<std::string> orientation_lines(std::string_view payload, ba::MachineType machine) {
    const acq::TestResult r = acq::test_from_json(payload);
    std::string line = "test " + std::to_string(r.test + 1) + " (" + std::string(acq::to_string(r.kind)) + "):";
    if (!r.orientation.exact)
        return {line + " orientation singular" + (r.orientation.singular.empty() ? "" : ": " + r.orientation.singular)};
    const ba::MeasuredAngles measured = acq::measured_angles(machine, r.kind);
    const ba::OrientationErrors& e = *r.orientation.exact;
    const ba::OrientationErrors s = r.std_rad.value_or(ba::OrientationErrors{});
    auto add = [&line](const char* symbol, double v, double sd) {
        line += std::string(" ") + symbol + " " + with_uncertainty(ba::rad_to_arcsec(v), ba::rad_to_arcsec(sd), "″");
    };
    if (measured.alpha) add("Δα", e.d_alpha_rad, s.d_alpha_rad);
    if (measured.beta) add("Δβ", e.d_beta_rad, s.d_beta_rad);
    if (measured.gamma) add("Δγ", e.d_gamma_rad, s.d_gamma_rad);
    return {line};
}

std::vector<std::string> identification_lines(std::string_view payload) {
    const storage::IdentificationRecord r = storage::identification_from_json(payload);
    char buf[200];
    std::snprintf(buf, sizeof buf, "%s, %d readings, residual RMS %.3f µm", r.converged ? "converged" : "NOT converged",
                  r.readings, r.residual_rms_um);
    std::vector<std::string> out{buf};
    std::string line;
    for (const auto& e : r.estimates) {
        if (!e.observable) continue;
        ScreenUnit u{1e3, "µm"};  // socket offsets: mm
        if (const auto p = ba::parse_param(e.name)) u = screen_unit(ba::param_info(*p).unit);
        const std::string item = e.name + " " + with_uncertainty(e.estimate * u.factor, e.std * u.factor, u.symbol);
        if (!line.empty() && line.size() + item.size() > 100) {
            out.push_back(line);
            line.clear();
        }
        line += (line.empty() ? "" : ", ") + item;
    }
    if (!line.empty()) out.push_back(line);
    return out;
}

std::vector<std::string> discovery_lines(const std::string& payload) {
    const storage::DiscoveryRecord r = storage::discovery_from_json(payload);
    char buf[200];
    std::snprintf(buf, sizeof buf, "residual RMS %.3f µm -> %.3f µm", r.rms_initial_um.value_or(0),
                  r.rms_final_um.value_or(0));
    std::vector<std::string> out{buf};
    if (!r.model_name.empty())
        out.back() += ", model " + r.model_name + " version " + std::to_string(r.model_version.value_or(0));
    for (const auto& st : r.steps) {
        if (st.kind != "library" || !st.value) continue;
        ScreenUnit u{1, st.unit};
        if (const auto p = ba::parse_param(st.iso)) u = screen_unit(ba::param_info(*p).unit);
        out.push_back(st.effect + " " +
                      with_uncertainty(*st.value * u.factor, st.value_std.value_or(0) * u.factor, u.symbol) +
                      (st.accepted.value_or(true) ? "" : " (withdrawn)"));
    }
    return out;
}

std::vector<std::string> compensation_lines(const std::string& payload) {
    const storage::CompensationRecord c = storage::compensation_from_json(payload);
    std::string line = "RMS error before -> after:";
    for (const auto& a : c.axes) {
        char buf[96];
        std::snprintf(buf, sizeof buf, " %s %.3f -> %.3f µm", a.axis.c_str(), a.before_um, a.after_um);
        line += buf;
    }
    return {line};
}
std::vector<std::string> instrument_lines(const std::string& payload) {
    const storage::GaugeInstrumentRecord r = storage::gauge_instrument_from_json(payload);
    char buf[200];
    std::snprintf(buf, sizeof buf, "%s %s, resolution %.4g µm, %.1f readings/s measured", r.maker.c_str(),
                  (r.model.empty() ? r.kind : r.model).c_str(), r.resolution_mm * 1e3, r.reading_rate_hz);
    return {buf};
}

/// Top-level numbers under their own names (the names carry the units), at most eight.
std::vector<std::string> generic_lines(const json& j) {
    std::string line;
    int shown = 0;
    for (const auto& [key, v] : j.items()) {
        if (!v.is_number() || ++shown > 8) continue;
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.6g", v.get<double>());
        line += (line.empty() ? "" : ", ") + key + " " + buf;
    }
    if (line.empty()) return {};
    return {line};
}

}  // namespace

std::vector<std::string> result_lines(std::string_view kind, std::string_view payload_json, ba::MachineType machine) {
    const json j = json::parse(payload_json, nullptr, false);
    if (j.is_discarded() || !j.is_object()) return {};
    try {
        if (kind == acq::kSsmResultKind) return ssm_lines(payload_json);
        if (kind == acq::kOrientationResultKind) return orientation_lines(payload_json, machine);
        if (kind == storage::kIdentificationResultKind) return identification_lines(payload_json);
        if (kind == storage::kDiscoveryResultKind) return discovery_lines(std::string(payload_json));
        if (kind == storage::kCompensationResultKind) return compensation_lines(std::string(payload_json));
        if (kind == storage::kInstrumentResultKind) return instrument_lines(std::string(payload_json));
        if (kind == "acquisition.plan") return {};  // the plan: `sessions show --json`
        return generic_lines(j);
    } catch (const json::exception&) {
        return {"(values not readable: " + std::string(kind) + " payload of another shape)"};
    } catch (const acq::ResultFormatError& e) {
        return {std::string("(values not readable: ") + e.what() + ")"};
    } catch (const storage::FormatError& e) {
        return {std::string("(values not readable: ") + e.what() + ")"};
    }
}

}  // namespace ballbar::app
