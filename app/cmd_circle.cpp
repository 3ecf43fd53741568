// SPDX-License-Identifier: MIT
// `ballbar circle plan|analyze`: the ISO 230-4 circular test (docs/circular.md).
//   plan     writes the part program of a circular test (Fanuc or LinuxCNC) and its test header
//   analyze  G, G(b), F and the diagnostics of a ballbar-trace/1 file or a stored circular session;
//            --controller prints the measured backlash (and scale) in a controller's own terms
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "ballbar/acquisition/circle_program.hpp"
#include "ballbar/acquisition/machine_file.hpp"
#include "ballbar/analysis/circular.hpp"
#include "ballbar/analysis/limits.hpp"
#include "ballbar/analysis/nc_program.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/storage/trace_file.hpp"
#include "circle_measure.hpp"
#include "circle_output.hpp"
#include "circle_test_options.hpp"
#include "command.hpp"
#include "files.hpp"

namespace ballbar::app {
namespace {

namespace circ = analysis::circular;

struct PlanOptions {
    CircleTestOptions test;
    std::string dialect;
    std::string machine_file;
    std::string out = "-";
    std::string test_out;
    double dwell_s = 1.0;
    std::optional<double> rate_hz;
    bool store = false;
};

/// Numbers in messages as the part program writes them (4 decimals, trailing zeros dropped).
std::string num_text(double v) {
    return acquisition::nc_number(v);
}

/// --rate: refuses a feed whose samples lie too far apart along the path for the diagnosis
/// (circ::sampling_limit), naming the highest usable feed.
void check_feed_for_rate(const circ::TestSpec& t, std::optional<double> rate) {
    if (!rate) return;
    const double rate_hz = *rate;
    if (!(rate_hz > 0.0) || !std::isfinite(rate_hz))
        throw Error(ErrorCategory::bad_input, "--rate must be a reading rate > 0, readings/s");
    const circ::SamplingLimit lim = circ::sampling_limit(t, rate_hz);
    const double spacing_mm = t.feed_mm_min / (60.0 * rate_hz);
    const std::string need = std::string(lim.binding) == "feed-in"
                                 ? "three samples on the " + num_text(t.feed_in_mm) + " mm feed-in"
                                 : "two samples per " + num_text(analysis::circular::AnalysisOptions{}.min_pitch_mm) +
                                       " mm cyclic-error pitch";
    const double highest = std::floor(lim.max_feed_mm_min + 1e-6);
    if (spacing_mm <= lim.max_spacing_mm * (1.0 + 1e-9)) {
        std::cerr << "ballbar: at " << num_text(rate_hz) << " readings/s the samples lie " << num_text(spacing_mm)
                  << " mm apart along the path (at most " << num_text(lim.max_spacing_mm) << " mm: " << need
                  << "); the highest usable feed is " << num_text(highest) << " mm/min\n";
        return;
    }
    throw Error(ErrorCategory::bad_input,
                "--feed " + num_text(t.feed_mm_min) + " mm/min is too fast for " + num_text(rate_hz) +
                    " readings/s: the samples would lie " + num_text(spacing_mm) +
                    " mm apart along the path, and the diagnosis needs at most " + num_text(lim.max_spacing_mm) +
                    " mm (" + need + "); the highest usable feed is " + num_text(highest) + " mm/min (--feed " +
                    num_text(highest) + ")");
}

/// The part program of trace.md's "The motion", run by run, arcs split into ≤ 90° blocks.
std::string circle_program(const circ::TestSpec& t, analysis::NcDialect dialect, double dwell_s,
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

int run_plan(const PlanOptions& o, const Globals& globals) {
    const circ::TestSpec t = circle_test(o.test);
    check_feed_for_rate(t, o.rate_hz);
    std::optional<acquisition::MachineFile> machine;
    if (!o.machine_file.empty()) {
        try {
            machine = acquisition::parse_machine_file(read_file(o.machine_file, "machine file"));
        } catch (const std::exception& e) {
            if (dynamic_cast<const Error*>(&e)) throw;
            throw Error(ErrorCategory::bad_input, o.machine_file + ": " + e.what());
        }
    }
    analysis::NcDialect dialect = machine ? machine->dialect : analysis::NcDialect::Fanuc;
    if (!o.dialect.empty()) {
        const auto d = analysis::parse_nc_dialect(o.dialect);
        if (!d) throw Error(ErrorCategory::bad_input, "--dialect must be fanuc or linuxcnc");
        dialect = *d;
    }
    std::vector<fileio::Protected> inputs = database_files(globals);
    if (!o.machine_file.empty()) inputs.push_back({o.machine_file, "machine file"});
    try {  // both outputs checked before either is written
        fileio::check_output(o.out, "--out", inputs);
        if (!o.test_out.empty()) {
            fileio::check_output(o.test_out, "--test-out", inputs);
            fileio::check_distinct_outputs(o.out, "--out", o.test_out, "--test-out");
        }
    } catch (const fileio::FileError& e) {
        throw as_error(e);
    }
    write_output(o.out, "--out", circle_program(t, dialect, o.dwell_s, machine ? &*machine : nullptr), inputs);
    if (o.out != "-") inputs.push_back({o.out, "program just written (--out)"});
    const std::string header = storage::test_json(t);
    if (!o.test_out.empty()) write_output(o.test_out, "--test-out", header + "\n", inputs);
    std::cerr << "ballbar: test header: " << header << '\n';
    if (o.store) {
        // A planned circular session: the test header it implies, waiting for its samples.
        try {
            storage::Store store(resolve_db_path(globals));
            storage::NewSession ns;
            ns.machine.name = "circular test";
            ns.procedure = "circular";
            ns.notes = "planned by circle plan";
            const nlohmann::ordered_json meta = {{"format", "ballbar-trace/1"},
                                                 {"test", nlohmann::ordered_json::parse(header)},
                                                 {"reference_length_mm", t.radius_mm + 0.5 * t.feed_in_mm},
                                                 {"has_bar_temp", false},
                                                 {"planned", true}};
            ns.metadata_json = meta.dump();
            const auto id = store.create_session(ns);
            std::cerr << "ballbar: planned session " << id << " (" << store.session(id).uuid << ")\n";
        } catch (const storage::StorageError& e) {
            throw as_error(e);
        }
    }
    return kExitOk;
}

struct AnalyzeOptions {
    std::vector<std::string> inputs;
    bool json = false;
    bool store = false;
    std::optional<double> tolerance_um;
    std::string controller;
};

struct Loaded {
    storage::TraceFile trace;
    std::optional<std::int64_t> session;
    std::string name;
};

Loaded load_input(const std::string& input, const Globals& globals, bool store_file) {
    Loaded l;
    l.name = input;
    std::error_code ec;
    if (std::filesystem::exists(std::filesystem::symlink_status(input, ec))) {  // a path: fileio says what it is
        try {
            l.trace = storage::read_trace_file(input);
        } catch (const storage::TraceFileError& e) {
            throw Error(ErrorCategory::bad_input, input + ": " + e.what());
        }
        for (const auto& w : l.trace.warnings) std::cerr << "ballbar: warning: " << input << ": " << w << '\n';
        if (store_file) {
            storage::Store store(resolve_db_path(globals));
            l.session = storage::import_trace(store, l.trace, input);
        }
        return l;
    }
    if (!looks_like_session_key(input)) throw Error(ErrorCategory::bad_input, input + ": no such file");
    storage::StoreOptions so;
    so.recover = false;
    storage::Store store(existing_db_path(globals), so);  // a session is looked for, never a database made
    note_database_damage(store.damage());
    const auto id = store.find_session(input);
    try {
        l.trace = storage::load_trace(store, id);
    } catch (const storage::StorageError&) {
        throw;
    } catch (const std::exception& e) {
        throw Error(ErrorCategory::bad_input, e.what());
    }
    l.session = id;
    return l;
}

int run_analyze(const AnalyzeOptions& o, const Globals& globals) {
    std::vector<circ::CircularResult> results;
    std::vector<Loaded> inputs;
    try {
        for (const auto& in : o.inputs) {
            inputs.push_back(load_input(in, globals, o.store));
            try {
                results.push_back(circ::analyze_circular(inputs.back().trace.test, inputs.back().trace.samples));
            } catch (const circ::CircularError& e) {
                throw Error(ErrorCategory::bad_input, in + ": " + e.what());
            }
        }
        nlohmann::ordered_json all = nlohmann::ordered_json::array();
        for (std::size_t i = 0; i < results.size(); ++i) {
            auto j = circle_result_json(results[i], inputs[i].trace, o.tolerance_um);
            if (!o.controller.empty()) j["controller"] = controller_json(results[i], o.controller);
            if (inputs[i].session) {
                storage::Store store(resolve_db_path(globals));
                store.add_result(*inputs[i].session, "circular", j.dump(), std::nullopt, "ballbar circular/1");
                j["session"] = *inputs[i].session;
            }
            all.push_back(j);
        }
        std::optional<circ::VolumetricResult> vol;
        if (results.size() > 1) {
            try {
                vol = circ::combine_volumetric(results);
            } catch (const circ::CircularError& e) {
                throw Error(ErrorCategory::bad_input, e.what());
            }
        }
        if (o.json) {
            if (results.size() == 1) {
                std::cout << all[0].dump(2) << '\n';
            } else {
                nlohmann::ordered_json j = {{"tests", all}, {"volumetric", volumetric_json(*vol)}};
                std::cout << j.dump(2) << '\n';
            }
        } else {
            for (std::size_t i = 0; i < results.size(); ++i) {
                std::cout << (results.size() > 1 ? "== " + inputs[i].name + "\n" : "");
                print_circle_result(std::cout, results[i], inputs[i].trace, o.tolerance_um);
                if (!o.controller.empty()) print_controller(std::cout, results[i], o.controller);
                if (inputs[i].session) std::cout << "stored with session " << *inputs[i].session << '\n';
            }
            if (vol) print_volumetric(std::cout, *vol);
        }
        if (o.tolerance_um) {
            for (const auto& r : results)
                for (const auto& run : r.runs)
                    if (run.circularity_um > *o.tolerance_um) return kExitFailure;
        }
        return kExitOk;
    } catch (const storage::StorageError& e) {
        throw as_error(e);
    }
}

}  // namespace
}  // namespace ballbar::app

BALLBAR_COMMAND(circle) {
    using namespace ballbar::app;
    auto* circle = root.add_subcommand("circle", "The ISO 230-4 circular test: plan, measure, analyze");
    circle->require_subcommand(1);

    auto po = std::make_shared<PlanOptions>();
    auto* plan = circle->add_subcommand("plan", "Write the part program of a circular test");
    plan->add_option("--plane", po->test.plane, "XY, YZ or ZX")->capture_default_str();
    add_circle_geometry_options(*plan, po->test, "feed of every move, mm/min");
    plan->add_option("--rate", po->rate_hz,
                     "the instrument's reading rate, readings/s: refuse a feed too fast for it (gauges: 10-50)")
        ->check(in_range(1, 100000, "readings/s"));
    plan->add_option("--feed-in", po->test.feed_in_mm, "radial feed-in and feed-out, mm")
        ->check(in_range(0, 10, "mm", true))
        ->capture_default_str();
    plan->add_option("--arc", po->test.arc_deg, "data arc, degrees (360 full circle; 180 the partial arc)")
        ->check(in_range(30, 360, "°"))
        ->capture_default_str();
    plan->add_option("--overshoot", po->test.overshoot_deg,
                     "overshoot each side, degrees (default 45 full, 20 partial)")
        ->check(in_range(0, 360, "°"));
    plan->add_option("--start", po->test.start_deg, "start angle of the first run, degrees (default 0 / −overshoot)")
        ->check(in_range(-36000, 36000, "°"));
    plan->add_option("--directions", po->test.directions, "both, ccw or cw")
        ->check(CLI::IsMember({"both", "ccw", "cw"}))
        ->capture_default_str();
    plan->add_option("--dialect", po->dialect, "fanuc or linuxcnc (default: the machine file's, else fanuc)");
    plan->add_option("--machine", po->machine_file, "machine file: travel limits and dialect");
    plan->add_option("--dwell", po->dwell_s, "stand still before each feed-in and at the end, s")
        ->check(in_range(0, 3600, "s"))
        ->capture_default_str();
    plan->add_option("--out", po->out, "program file (- for stdout)")->capture_default_str();
    plan->add_option("--test-out", po->test_out, "write the test header (JSON) to this file too");
    plan->add_flag("--store", po->store, "create a planned circular session holding the test header");
    plan->callback([po, &globals] { globals.action = [po, &globals] { return run_plan(*po, globals); }; });

    auto ao = std::make_shared<AnalyzeOptions>();
    auto* an = circle->add_subcommand("analyze", "G, G(b), F and the diagnostics of a circular test");
    an->add_option("INPUT", ao->inputs, "ballbar-trace/1 file or stored session (several: volumetric summary)")
        ->required();
    an->add_flag("--json", ao->json, "print the result as JSON");
    an->add_flag("--store", ao->store, "import a trace file as a session and store the result with it");
    an->add_option("--tolerance", ao->tolerance_um, "circular deviation G allowed, µm: pass/fail (exit 1 on fail)")
        ->check(in_range(0, 10000, "µm", true));
    an->add_option("--controller", ao->controller,
                   "print backlash/scale settings: linuxcnc, marlin, smoothieware, grblhal")
        ->check(CLI::IsMember({"linuxcnc", "marlin", "smoothieware", "grblhal"}));
    an->callback([ao, &globals] { globals.action = [ao, &globals] { return run_analyze(*ao, globals); }; });
    add_circle_measure(*circle, globals);  // circle measure (cmd_circle_measure.cpp)
}
