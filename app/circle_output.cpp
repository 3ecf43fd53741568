// SPDX-License-Identifier: MIT
// Text and JSON of a circular test's result; controller settings from the measured backlash/scale.
#include "circle_output.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace ballbar::app {
namespace {

namespace circ = analysis::circular;
using json = nlohmann::ordered_json;

std::string fmt(double v, int decimals = 2) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    return buf;
}

struct AxisFigures {
    char axis = 'x';
    int index = 0;
    std::optional<double> backlash_um, scale_ppm;
};

/// Backlash and scale of the plane's two axes. Scale: the mismatch (s_p − s_q) and the mean radius
/// offset (s_p + s_q)/2 · R (the bar's length is absolute) give each axis's own scale error.
std::array<AxisFigures, 2> axis_figures(const circ::CircularResult& r) {
    const auto letters = circ::plane_axes(r.test.plane);
    const auto idx = circ::plane_axis_index(r.test.plane);
    std::array<AxisFigures, 2> out{};
    out[0].axis = letters[0], out[0].index = idx[0], out[1].axis = letters[1], out[1].index = idx[1];
    if (const auto* b = r.find(circ::Diag::BacklashP)) out[0].backlash_um = b->value;
    if (const auto* b = r.find(circ::Diag::BacklashQ)) out[1].backlash_um = b->value;
    if (const auto* m = r.find(circ::Diag::ScaleMismatch)) {
        const double mean_ppm = r.mean_radius_um * 1e3 / r.test.radius_mm;
        out[0].scale_ppm = mean_ppm + 0.5 * m->value;
        out[1].scale_ppm = mean_ppm - 0.5 * m->value;
    }
    return out;
}

}  // namespace

json circle_result_json(const circ::CircularResult& r, const storage::TraceFile& trace,
                        std::optional<double> tolerance_um) {
    json j;
    j["test"] = json::parse(storage::test_json(r.test));
    json runs = json::array();
    for (const auto& run : r.runs)
        runs.push_back({{"direction", circ::direction_name(run.direction)},
                        {"circularity_um", run.circularity_um},
                        {"radial_deviation_um", {{"max", run.radial_max_um}, {"min", run.radial_min_um}}},
                        {"feed_in_end_s", run.feed_in_end_s},
                        {"feed_in_lag_ms", run.servo_lag_s * 1e3},
                        {"data_start_s", run.data_start_s},
                        {"data_end_s", run.data_end_s},
                        {"samples", run.last_sample - run.first_sample}});
    j["runs"] = runs;
    j["bidirectional_circularity_um"] = r.bidirectional_um ? json(*r.bidirectional_um) : json(nullptr);
    j["radial_deviation_um"] = {{"max", r.radial_max_um}, {"min", r.radial_min_um}};
    json diags = json::object(), unc = json::object(), share = json::object(), ranking = json::array(),
         missing = json::array();
    for (const auto& d : r.diagnostics) {
        if (!d.detected) {
            missing.push_back(d.key);
            continue;
        }
        diags[d.key] = d.value;
        unc[d.key] = d.std_uncertainty;
        if (d.contribution_um > 0.0) {
            share[d.key] = d.share_percent;
            ranking.push_back(d.key);
        }
    }
    j["diagnostics"] = diags;
    j["uncertainties"] = unc;
    j["shares_percent"] = share;
    j["ranking"] = ranking;
    j["not_detected"] = missing;
    json groups = json::array();
    for (const auto& g : r.unseparable) {
        json e = {{"keys", g.keys}, {"reason", g.reason}};
        if (!g.combined_key.empty())
            e["combined"] = {{"as", g.combined_key}, {"value", g.combined_value}, {"std_uncertainty", g.combined_std}};
        groups.push_back(e);
    }
    j["unseparable"] = groups;
    j["residual_rms_um"] = r.residual_rms_um;
    j["mean_radius_um"] = {{"value", r.mean_radius_um}, {"std_uncertainty", r.mean_radius_std_um}};
    json cond = {{"plane", circ::plane_name(r.test.plane)},
                 {"radius_mm", r.test.radius_mm},
                 {"feed_mm_min", r.test.feed_mm_min},
                 {"sample_rate_hz", r.sample_rate_hz},
                 {"samples_used", r.samples_used}};
    auto range = [](const std::vector<std::optional<double>>& v) -> json {
        double lo = 1e300, hi = -1e300;
        for (const auto& x : v)
            if (x) lo = std::min(lo, *x), hi = std::max(hi, *x);
        return lo <= hi ? json{{"min", lo}, {"max", hi}} : json(nullptr);
    };
    cond["bar_temp_C"] = range(trace.bar_temp_C);
    cond["air_temp_C"] = range(trace.air_temp_C);
    cond["instrument"] = trace.instrument_json.empty() ? json(nullptr) : json::parse(trace.instrument_json);
    j["conditions"] = cond;
    if (tolerance_um) {
        bool pass = true;
        for (const auto& run : r.runs) pass = pass && run.circularity_um <= *tolerance_um;
        j["tolerance"] = {{"circularity_um", *tolerance_um}, {"pass", pass}};
    }
    return j;
}

void print_circle_result(std::ostream& os, const circ::CircularResult& r, const storage::TraceFile& trace,
                         std::optional<double> tolerance_um) {
    os << "circular test " << circ::plane_name(r.test.plane) << ", radius " << fmt(r.test.radius_mm, 1) << " mm, feed "
       << fmt(r.test.feed_mm_min, 0) << " mm/min, " << fmt(r.sample_rate_hz, 0) << " Hz, " << r.runs.size()
       << " run(s)";
    if (!trace.instrument_json.empty()) os << ", instrument " << trace.instrument_json;
    os << '\n';
    for (std::size_t k = 0; k < r.runs.size(); ++k)
        os << "  run " << k + 1 << " " << circ::direction_name(r.runs[k].direction) << ": G "
           << fmt(r.runs[k].circularity_um) << " um  (data from " << fmt(r.runs[k].data_start_s, 3) << " s to "
           << fmt(r.runs[k].data_end_s, 3) << " s)\n";
    if (r.bidirectional_um) os << "  G(b) " << fmt(*r.bidirectional_um) << " um\n";
    os << "  F max " << fmt(r.radial_max_um) << " um, min " << fmt(r.radial_min_um) << " um\n";
    if (tolerance_um) {
        bool pass = true;
        for (const auto& run : r.runs) pass = pass && run.circularity_um <= *tolerance_um;
        os << "  tolerance G <= " << fmt(*tolerance_um) << " um: " << (pass ? "PASS" : "FAIL") << '\n';
    }
    os << "diagnostics, ranked by share of the circular deviation (value ± standard uncertainty):\n";
    std::string missing;
    for (const auto& d : r.diagnostics) {
        if (!d.detected) {
            missing += (missing.empty() ? "" : ", ") + d.key;
            continue;
        }
        char line[160];
        std::snprintf(line, sizeof line, "  %-26s %10.3f ± %-8.3f %-5s", d.key.c_str(), d.value, d.std_uncertainty,
                      circ::diagnostic_unit(d.diag));
        os << line;
        if (d.contribution_um > 0.0) os << "  " << fmt(d.share_percent, 1) << " %";
        os << '\n';
    }
    if (!missing.empty()) os << "not detected: " << missing << '\n';
    for (const auto& g : r.unseparable) {
        os << "cannot be separated: ";
        for (std::size_t i = 0; i < g.keys.size(); ++i) os << (i ? " + " : "") << g.keys[i];
        os << " (" << g.reason << ")";
        if (!g.combined_key.empty())
            os << "; together as " << g.combined_key << " " << fmt(g.combined_value, 3) << " ± "
               << fmt(g.combined_std, 3);
        os << '\n';
    }
    os << "residual RMS after the diagnosis: " << fmt(r.residual_rms_um, 3) << " um\n";
}

json volumetric_json(const circ::VolumetricResult& v) {
    json j = json::object();
    for (const auto& f : v.figures)
        j[f.key] = f.known ? json{{"value", f.value}, {"std_uncertainty", f.std_uncertainty}} : json(nullptr);
    return j;
}

void print_volumetric(std::ostream& os, const circ::VolumetricResult& v) {
    os << "volumetric summary:\n";
    for (const auto& f : v.figures) {
        os << "  " << f.key << ": ";
        if (f.known)
            os << fmt(f.value, 3) << " ± " << fmt(f.std_uncertainty, 3) << '\n';
        else
            os << "not determined by these planes\n";
    }
}

json controller_json(const circ::CircularResult& r, const std::string& controller) {
    json j = {{"controller", controller}};
    json axes = json::object();
    const char* grbl_backlash[3] = {"$160", "$161", "$162"};
    const char* grbl_steps[3] = {"$100", "$101", "$102"};
    for (const auto& a : axis_figures(r)) {
        json e = json::object();
        const std::string axis(1, static_cast<char>(a.axis - 'a' + 'A'));
        if (a.backlash_um) {
            const double mm = std::max(*a.backlash_um, 0.0) * 1e-3;
            e["backlash_mm"] = mm;
            if (*a.backlash_um < 0.0) e["note"] = "negative lost motion (the axis overshoots): not compensable, set 0";
            if (controller == "linuxcnc")
                e["setting"] = "[JOINT_" + std::to_string(a.index) + "] BACKLASH = " + fmt(mm, 4);
            else if (controller == "grblhal")
                e["setting"] = std::string(grbl_backlash[a.index]) + "=" + fmt(mm, 4);
            else
                e["setting"] = "M425 " + axis + fmt(mm, 4);
        }
        if (a.scale_ppm) {
            const double factor = 1.0 / (1.0 + *a.scale_ppm * 1e-6);
            e["scale_ppm"] = *a.scale_ppm;
            e["steps_per_mm_factor"] = factor;
            if (controller == "linuxcnc")
                e["scale_setting"] =
                    "[JOINT_" + std::to_string(a.index) + "] SCALE = current SCALE × " + fmt(factor, 7);
            else if (controller == "grblhal")
                e["scale_setting"] = std::string(grbl_steps[a.index]) + " = current × " + fmt(factor, 7);
            else
                e["scale_setting"] = "M92 " + axis + "<current steps/mm × " + fmt(factor, 7) + ">";
        }
        axes[axis] = e;
    }
    j["axes"] = axes;
    return j;
}

void print_controller(std::ostream& os, const circ::CircularResult& r, const std::string& controller) {
    const json j = controller_json(r, controller);
    os << controller << " settings from this test (backlash: the lost motion measured, added at each reversal):\n";
    for (const auto& [axis, e] : j["axes"].items()) {
        if (e.contains("setting")) os << "  " << e["setting"].get<std::string>() << "   ; " << axis << " backlash\n";
        if (e.contains("note")) os << "  ; " << axis << ": " << e["note"].get<std::string>() << '\n';
        if (e.contains("scale_setting"))
            os << "  " << e["scale_setting"].get<std::string>() << "   ; " << axis << " scale error "
               << fmt(e["scale_ppm"].get<double>(), 1) << " ppm\n";
    }
    if (controller == "marlin" || controller == "smoothieware") os << "  M500   ; keep them (Marlin: EEPROM)\n";
}

}  // namespace ballbar::app
