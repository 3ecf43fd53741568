// SPDX-License-Identifier: MIT
// Text and JSON of a circular test's result; controller settings from the measured backlash/scale.
#include "circle_output.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "ballbar/storage/circular_result.hpp"

namespace ballbar::app {
namespace {

namespace circ = analysis::circular;
using ojson = nlohmann::ordered_json;

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

ojson circle_result_json(const circ::CircularResult& r, const storage::TraceFile& trace,
                         std::optional<double> tolerance_um) {
    return ojson::parse(storage::circular_result_json(r, trace, tolerance_um));  // the stored payload's format
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
                      circ::diagnostic_unit_symbol(d.diag));
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

ojson volumetric_json(const circ::VolumetricResult& v) {
    ojson j = ojson::object();
    for (const auto& f : v.figures)
        j[f.key] = f.known ? ojson{{"value", f.value}, {"value_std", f.std_uncertainty}} : ojson(nullptr);
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

ojson controller_json(const circ::CircularResult& r, const std::string& controller) {
    ojson j = {{"controller", controller}};
    ojson axes = ojson::object();
    // grblHAL: axis settings are numbered 100 + 10·kind + axis (X 0, Y 1, Z 2); kind 0 steps/mm,
    // kind 6 backlash (mm, only in a build with ENABLE_BACKLASH_COMPENSATION).
    const char* smoothie_actuator[3] = {"alpha", "beta", "gamma"};
    for (const auto& a : axis_figures(r)) {
        ojson e = ojson::object();
        const std::string axis(1, static_cast<char>(a.axis - 'a' + 'A'));
        const std::string index = std::to_string(a.index);
        if (a.backlash_um) {
            const double mm = std::max(*a.backlash_um, 0.0) * 1e-3;
            e["backlash_mm"] = mm;
            if (*a.backlash_um < 0.0) e["note"] = "negative lost motion (the axis overshoots): not compensable, set 0";
            if (controller == "linuxcnc") {
                e["setting"] = "[JOINT_" + index + "] BACKLASH = " + fmt(mm, 4);
            } else if (controller == "grblhal") {
                e["setting"] = "$16" + index + "=" + fmt(mm, 3);
            } else if (controller == "smoothieware") {
                e["setting"] = "M425 " + axis + fmt(mm, 4) + " P1";
                e["config"] = "[actuator] " + std::string(smoothie_actuator[a.index]) + ".backlash_mm = " + fmt(mm, 4);
            } else {
                e["setting"] = "M425 " + axis + fmt(mm, 4) + " F1";  // F1: full correction (Marlin's default is 0)
            }
        }
        if (a.scale_ppm) {
            const double factor = 1.0 / (1.0 + *a.scale_ppm * 1e-6);
            e["scale_ppm"] = *a.scale_ppm;
            e["steps_per_mm_factor"] = factor;
            if (controller == "linuxcnc")
                e["scale_setting"] = "[JOINT_" + index + "] SCALE = current SCALE × " + fmt(factor, 7);
            else if (controller == "grblhal")
                e["scale_setting"] = "$10" + index + " = current × " + fmt(factor, 7);
            else if (controller == "smoothieware")
                e["scale_setting"] = "[actuator] " + std::string(smoothie_actuator[a.index]) +
                                     ".steps_per_mm = current × " + fmt(factor, 7);
            else
                e["scale_setting"] = "M92 " + axis + "<current steps/mm × " + fmt(factor, 7) + ">";
        }
        axes[axis] = e;
    }
    j["axes"] = axes;
    if (controller == "smoothieware")
        j["config"] = "[motion control] backlash_enable = true";  // SmoothieV2: on at every boot
    return j;
}

void print_controller(std::ostream& os, const circ::CircularResult& r, const std::string& controller) {
    const ojson j = controller_json(r, controller);
    os << controller << " settings from this test (backlash: the lost motion measured, added at each reversal):\n";
    for (const auto& [axis, e] : j["axes"].items()) {
        if (e.contains("setting")) os << "  " << e["setting"].get<std::string>() << "   ; " << axis << " backlash\n";
        if (e.contains("note")) os << "  ; " << axis << ": " << e["note"].get<std::string>() << '\n';
        if (e.contains("scale_setting"))
            os << "  " << e["scale_setting"].get<std::string>() << "   ; " << axis << " scale error "
               << fmt(e["scale_ppm"].get<double>(), 1) << " ppm\n";
    }
    if (controller == "linuxcnc")
        os << "  ; machine units: mm (an inch machine: / 25.4); joints 0, 1, 2 = X, Y, Z (trivkins); with BACKLASH,\n"
              "  ; give the step generator headroom (STEPGEN_MAXACCEL about twice MAX_ACCELERATION)\n";
    if (controller == "marlin") os << "  M500   ; keep them (EEPROM); Marlin built with BACKLASH_GCODE\n";
    if (controller == "grblhal")
        os << "  ; grblHAL built with ENABLE_BACKLASH_COMPENSATION; it starts from the homing direction ($23)\n";
    if (controller == "smoothieware") {
        os << "  ; SmoothieV2 (version 1 has no backlash compensation): M425 sets it until power-off; to keep it,\n"
              "  ; config.ini:\n";
        for (const auto& [axis, e] : j["axes"].items())
            if (e.contains("config")) os << "  ;   " << e["config"].get<std::string>() << '\n';
        os << "  ;   " << j["config"].get<std::string>() << '\n';
    }
}

}  // namespace ballbar::app
