// SPDX-License-Identifier: MIT
// Text and JSON of a circular test's result; controller settings from the measured backlash/scale.
#include "circle_output.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "ballbar/report/advice.hpp"
#include "ballbar/storage/circular_result.hpp"
#include "ballbar/workflow/circular_test.hpp"

namespace ballbar::app {
namespace {

namespace circ = analysis::circular;
using ojson = nlohmann::ordered_json;

std::string fmt(double v, int decimals = 2) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    return buf;
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
           << fmt(r.runs[k].circularity_um) << " µm  (data from " << fmt(r.runs[k].data_start_s, 3) << " s to "
           << fmt(r.runs[k].data_end_s, 3) << " s)\n";
    if (r.bidirectional_um) os << "  G(b) " << fmt(*r.bidirectional_um) << " µm\n";
    if (r.hysteresis_um) os << "  H " << fmt(*r.hysteresis_um) << " µm (circular hysteresis)\n";
    os << "  F max " << fmt(r.radial_max_um) << " µm, min " << fmt(r.radial_min_um) << " µm\n";
    if (tolerance_um) {
        bool pass = true;
        for (const auto& run : r.runs) pass = pass && run.circularity_um <= *tolerance_um;
        os << "  tolerance G ≤ " << fmt(*tolerance_um) << " µm: " << (pass ? "PASS" : "FAIL") << '\n';
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
        if (const std::string a =
                report::diagnostic_action(d.key, d.value, d.std_uncertainty, circ::plane_name(r.test.plane));
            !a.empty())
            os << "      → " << a << '\n';
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
    os << "residual RMS after the diagnosis: " << fmt(r.residual_rms_um, 3) << " µm\n";
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
    const workflow::ControllerSettings cs = workflow::controller_settings(r, controller);
    ojson j = {{"controller", controller}};
    ojson axes = ojson::object();
    for (const auto& a : cs.axes) {
        ojson e = ojson::object();
        if (a.backlash_mm) e["backlash_mm"] = *a.backlash_mm;
        if (!a.note.empty()) e["note"] = a.note;
        if (!a.setting.empty()) e["setting"] = a.setting;
        if (!a.config.empty()) e["config"] = a.config;
        if (a.scale_ppm) e["scale_ppm"] = *a.scale_ppm;
        if (a.steps_per_mm_factor) e["steps_per_mm_factor"] = *a.steps_per_mm_factor;
        if (!a.scale_setting.empty()) e["scale_setting"] = a.scale_setting;
        axes[std::string(1, a.axis)] = e;
    }
    j["axes"] = axes;
    if (!cs.config.empty()) j["config"] = cs.config;
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
