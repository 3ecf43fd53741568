// SPDX-License-Identifier: MIT
#include "ballbar/workflow/circular_test.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "ballbar/acquisition/circle_program.hpp"
#include "ballbar/acquisition/plan.hpp"
#include "ballbar/storage/circular_result.hpp"
#include "ballbar/workflow/error.hpp"
#include "ballbar/workflow/session_key.hpp"

namespace ballbar::workflow {
namespace {

namespace circ = analysis::circular;

/// Numbers in messages as the part program writes them (4 decimals, trailing zeros dropped).
std::string num_text(double v) {
    return acquisition::nc_number(v);
}

std::string fixed(double v, int decimals) {
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

CircularInput load_input(const std::string& input, const StoreOpener& sessions, const StoreOpener& for_writing,
                         bool import_file, std::vector<std::string>& warnings) {
    CircularInput in;
    in.name = input;
    std::error_code ec;
    if (std::filesystem::exists(std::filesystem::symlink_status(input, ec))) {  // a path: fileio says what it is
        try {
            in.trace = storage::read_trace_file(input);
        } catch (const storage::TraceFileError& e) {
            throw Error(ErrorCategory::bad_input, input + ": " + e.what());
        }
        for (const auto& w : in.trace.warnings) warnings.push_back(input + ": " + w);
        if (import_file) in.session = storage::import_trace(for_writing(), in.trace, input);
        return in;
    }
    if (!looks_like_session_key(input)) throw Error(ErrorCategory::bad_input, input + ": no such file");
    storage::Store& store = sessions();
    const auto id = store.find_session(input);
    try {
        in.trace = storage::load_trace(store, id);
    } catch (const storage::StorageError&) {
        throw;
    } catch (const std::exception& e) {  // not a circular test
        throw Error(ErrorCategory::bad_input, e.what());
    }
    in.session = id;
    return in;
}

}  // namespace

std::string check_feed_for_rate(const circ::TestSpec& t, double rate_hz) {
    if (!(rate_hz > 0.0) || !std::isfinite(rate_hz))
        throw Error(ErrorCategory::bad_input, "--rate must be a reading rate > 0, readings/s");
    const circ::SamplingLimit lim = circ::sampling_limit(t, rate_hz);
    const double spacing_mm = t.feed_mm_min / (60.0 * rate_hz);
    const std::string need =
        std::string(lim.binding) == "feed-in"
            ? "three samples on the " + num_text(t.feed_in_mm) + " mm feed-in"
            : "two samples per " + num_text(circ::AnalysisOptions{}.min_pitch_mm) + " mm cyclic-error pitch";
    const double highest = std::floor(lim.max_feed_mm_min + 1e-6);
    if (spacing_mm <= lim.max_spacing_mm * (1.0 + 1e-9))
        return "at " + num_text(rate_hz) + " readings/s the samples lie " + num_text(spacing_mm) +
               " mm apart along the path (at most " + num_text(lim.max_spacing_mm) + " mm: " + need +
               "); the highest usable feed is " + num_text(highest) + " mm/min";
    throw Error(ErrorCategory::bad_input,
                "--feed " + num_text(t.feed_mm_min) + " mm/min is too fast for " + num_text(rate_hz) +
                    " readings/s: the samples would lie " + num_text(spacing_mm) +
                    " mm apart along the path, and the diagnosis needs at most " + num_text(lim.max_spacing_mm) +
                    " mm (" + need + "); the highest usable feed is " + num_text(highest) + " mm/min (--feed " +
                    num_text(highest) + ")");
}

std::string circular_part_program(const circ::TestSpec& t, analysis::NcDialect dialect, double dwell_s,
                                  const acquisition::MachineFile* machine) {
    const auto ax = circ::plane_axis_index(t.plane);
    const char* letters = "XYZ";
    // Travel: every point of the path lies within radius R + feed-in of the centre.
    if (machine) {
        for (int i = 0; i < 3; ++i) {
            const auto& range = machine->range(static_cast<acquisition::Axis>(i));
            double lo = t.centre_mm[static_cast<std::size_t>(i)], hi = lo;
            if (i == ax[0] || i == ax[1]) lo -= t.radius_mm + t.feed_in_mm, hi += t.radius_mm + t.feed_in_mm;
            if (lo < range.min || hi > range.max)
                throw Error(ErrorCategory::bad_input, std::string("the test leaves the travel of ") + letters[i] +
                                                          ": it needs " + num_text(lo) + " .. " + num_text(hi) +
                                                          " mm, the machine has " + num_text(range.min) + " .. " +
                                                          num_text(range.max) + " mm");
        }
    }
    try {
        return acquisition::circular_program(t, dialect, dwell_s);
    } catch (const acquisition::PlanError& e) {
        throw Error(ErrorCategory::bad_input, e.what());
    }
}

std::int64_t store_planned_circular(storage::Store& store, const circ::TestSpec& test) {
    const std::string header = storage::test_json(test);
    storage::NewSession ns;
    ns.machine.name = "circular test";
    ns.procedure = "circular";
    ns.notes = "planned by circle plan";
    const nlohmann::ordered_json meta = {{"format", "ballbar-trace/1"},
                                         {"test", nlohmann::ordered_json::parse(header)},
                                         {"reference_length_mm", test.radius_mm + 0.5 * test.feed_in_mm},
                                         {"has_bar_temp", false},
                                         {"planned", true}};
    ns.metadata_json = meta.dump();
    return store.create_session(ns);
}

CircularAnalysis analyze_circular_inputs(std::span<const std::string> inputs, const StoreOpener& sessions,
                                         const StoreOpener& for_writing, const CircularAnalyzeOptions& options) {
    CircularAnalysis out;
    std::vector<circ::CircularResult> results;
    for (const auto& name : inputs) {
        AnalyzedCircular a;
        a.input = load_input(name, sessions, for_writing, options.import_files, out.warnings);
        try {
            a.result = circ::analyze_circular(a.input.trace.test, a.input.trace.samples);
        } catch (const circ::CircularError& e) {
            throw Error(ErrorCategory::bad_input, name + ": " + e.what());
        }
        a.payload_json = storage::circular_result_json(a.result, a.input.trace, options.tolerance_um);
        results.push_back(a.result);
        out.tests.push_back(std::move(a));
    }
    if (results.size() > 1) {
        try {
            out.volumetric = circ::combine_volumetric(results);
        } catch (const circ::CircularError& e) {
            throw Error(ErrorCategory::bad_input, e.what());
        }
    }
    // Stored once every input has been analysed: a refused input stores nothing. A session that already
    // holds this very result (the same trace analysed the same way) is not given a second copy.
    for (auto& a : out.tests) {
        if (!a.input.session) continue;
        storage::Store& store = for_writing();
        bool held = false;
        for (const auto& r : store.results(*a.input.session))
            held = held || (r.kind == "circular" && r.payload_json == a.payload_json);
        if (held) continue;
        store.add_result(*a.input.session, "circular", a.payload_json, std::nullopt, "ballbar circular/1");
        a.stored = true;
    }
    return out;
}

bool known_controller(const std::string& c) {
    return c == "linuxcnc" || c == "marlin" || c == "smoothieware" || c == "grblhal";
}

ControllerSettings controller_settings(const circ::CircularResult& r, const std::string& controller) {
    if (!known_controller(controller))
        throw Error(ErrorCategory::bad_input,
                    "controller '" + controller + "': linuxcnc, marlin, smoothieware or grblhal");
    ControllerSettings out;
    out.controller = controller;
    // grblHAL: axis settings are numbered 100 + 10·kind + axis (X 0, Y 1, Z 2); kind 0 steps/mm,
    // kind 6 backlash (mm, only in a build with ENABLE_BACKLASH_COMPENSATION).
    const char* smoothie_actuator[3] = {"alpha", "beta", "gamma"};
    for (const auto& a : axis_figures(r)) {
        AxisSetting e;
        e.axis = static_cast<char>(a.axis - 'a' + 'A');
        const std::string axis(1, e.axis);
        const std::string index = std::to_string(a.index);
        if (a.backlash_um) {
            const double mm = std::max(*a.backlash_um, 0.0) * 1e-3;
            e.backlash_mm = mm;
            if (*a.backlash_um < 0.0) e.note = "negative lost motion (the axis overshoots): not compensable, set 0";
            if (controller == "linuxcnc") {
                e.setting = "[JOINT_" + index + "] BACKLASH = " + fixed(mm, 4);
            } else if (controller == "grblhal") {
                e.setting = "$16" + index + "=" + fixed(mm, 3);
            } else if (controller == "smoothieware") {
                e.setting = "M425 " + axis + fixed(mm, 4) + " P1";
                e.config = "[actuator] " + std::string(smoothie_actuator[a.index]) + ".backlash_mm = " + fixed(mm, 4);
            } else {
                e.setting = "M425 " + axis + fixed(mm, 4) + " F1";  // F1: full correction (Marlin's default is 0)
            }
        }
        if (a.scale_ppm) {
            const double factor = 1.0 / (1.0 + *a.scale_ppm * 1e-6);
            e.scale_ppm = *a.scale_ppm;
            e.steps_per_mm_factor = factor;
            if (controller == "linuxcnc")
                e.scale_setting = "[JOINT_" + index + "] SCALE = current SCALE × " + fixed(factor, 7);
            else if (controller == "grblhal")
                e.scale_setting = "$10" + index + " = current × " + fixed(factor, 7);
            else if (controller == "smoothieware")
                e.scale_setting = "[actuator] " + std::string(smoothie_actuator[a.index]) +
                                  ".steps_per_mm = current × " + fixed(factor, 7);
            else
                e.scale_setting = "M92 " + axis + "<current steps/mm × " + fixed(factor, 7) + ">";
        }
        out.axes.push_back(e);
    }
    if (controller == "smoothieware")
        out.config = "[motion control] backlash_enable = true";  // SmoothieV2: on at every boot
    return out;
}

circ::TestSpec circular_test_spec(const CircularTestInput& o) {
    circ::TestSpec t;
    const auto plane = circ::parse_plane(o.plane);
    if (!plane) throw Error(ErrorCategory::bad_input, "--plane must be XY, YZ or ZX");
    t.plane = *plane;
    t.radius_mm = o.radius_mm;
    if (o.centre_mm.size() != 3) throw Error(ErrorCategory::bad_input, "--centre needs three numbers X Y Z");
    t.centre_mm = {o.centre_mm[0], o.centre_mm[1], o.centre_mm[2]};
    t.feed_mm_min = o.feed_mm_min;
    t.feed_in_mm = o.feed_in_mm;
    if (o.directions != "both" && o.directions != "ccw" && o.directions != "cw")
        throw Error(ErrorCategory::bad_input, "--directions must be both, ccw or cw");
    const bool full = o.arc_deg >= 360.0;
    const double over = o.overshoot_deg ? *o.overshoot_deg : full ? 45.0 : 20.0;  // (checked by validate())
    const double start = o.start_deg ? *o.start_deg : full ? 0.0 : -over;
    const double end = start + 2.0 * over + o.arc_deg;
    if (o.directions == "both" || o.directions == "ccw")
        t.runs.push_back({circ::Direction::Ccw, start, over, o.arc_deg});
    if (o.directions == "both") t.runs.push_back({circ::Direction::Cw, end, over, o.arc_deg});
    if (o.directions == "cw") t.runs.push_back({circ::Direction::Cw, start, over, o.arc_deg});
    if (const auto bad = t.validate(); !bad.empty()) throw Error(ErrorCategory::bad_input, bad);
    return t;
}

}  // namespace ballbar::workflow
