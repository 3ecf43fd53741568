// SPDX-License-Identifier: MIT
// `ballbar circle plan|analyze`: the ISO 230-4 circular test (docs/circular.md).
//   plan     writes the part program of a circular test (Fanuc or LinuxCNC) and its test header
//   analyze  G, G(b), F and the diagnostics of a ballbar-trace/1 file or a stored circular session;
//            --controller prints the measured backlash (and scale) in a controller's own terms
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "ballbar/acquisition/machine_file.hpp"
#include "ballbar/analysis/circular.hpp"
#include "ballbar/analysis/nc_program.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/storage/trace_file.hpp"
#include "ballbar/workflow/circular_test.hpp"
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

int run_plan(const PlanOptions& o, const Globals& globals) {
    const circ::TestSpec t = circle_test(o.test);
    if (o.rate_hz) std::cerr << "ballbar: " << workflow::check_feed_for_rate(t, *o.rate_hz) << '\n';
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
    write_output(o.out, "--out", workflow::circular_part_program(t, dialect, o.dwell_s, machine ? &*machine : nullptr),
                 inputs);
    if (o.out != "-") inputs.push_back({o.out, "program just written (--out)"});
    const std::string header = storage::test_json(t);
    if (!o.test_out.empty()) write_output(o.test_out, "--test-out", header + "\n", inputs);
    std::cerr << "ballbar: test header: " << header << '\n';
    if (o.store) {
        try {
            storage::Store store(resolve_db_path(globals));
            const auto id = workflow::store_planned_circular(store, t);
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

int run_analyze(const AnalyzeOptions& o, const Globals& globals) {
    std::optional<storage::Store> reader, writer;
    const workflow::StoreOpener sessions = [&]() -> storage::Store& {
        if (!reader) {
            storage::StoreOptions so;
            so.recover = false;                             // leave sessions of a running acquisition alone
            reader.emplace(existing_db_path(globals), so);  // a session is looked for, never a database made
            note_database_damage(reader->damage());
        }
        return *reader;
    };
    const workflow::StoreOpener for_writing = [&]() -> storage::Store& {
        if (!writer) writer.emplace(resolve_db_path(globals));
        return *writer;
    };
    workflow::CircularAnalyzeOptions ao;
    ao.import_files = o.store;
    ao.tolerance_um = o.tolerance_um;
    workflow::CircularAnalysis a;
    try {
        a = workflow::analyze_circular_inputs(o.inputs, sessions, for_writing, ao);
    } catch (const storage::StorageError& e) {
        throw as_error(e);
    }
    for (const auto& w : a.warnings) std::cerr << "ballbar: warning: " << w << '\n';
    if (o.json) {
        nlohmann::ordered_json all = nlohmann::ordered_json::array();
        for (const auto& t : a.tests) {
            auto j = nlohmann::ordered_json::parse(t.payload_json);
            if (!o.controller.empty()) j["controller"] = controller_json(t.result, o.controller);
            if (t.input.session) j["session"] = *t.input.session;
            all.push_back(j);
        }
        if (a.tests.size() == 1) {
            std::cout << all[0].dump(2) << '\n';
        } else {
            nlohmann::ordered_json j = {{"tests", all}, {"volumetric", volumetric_json(*a.volumetric)}};
            std::cout << j.dump(2) << '\n';
        }
    } else {
        for (const auto& t : a.tests) {
            std::cout << (a.tests.size() > 1 ? "== " + t.input.name + "\n" : "");
            print_circle_result(std::cout, t.result, t.input.trace, o.tolerance_um);
            if (!o.controller.empty()) print_controller(std::cout, t.result, o.controller);
            if (t.input.session)
                std::cout << (t.stored ? "stored with session " : "already stored with session ") << *t.input.session
                          << '\n';
        }
        if (a.volumetric) print_volumetric(std::cout, *a.volumetric);
    }
    if (o.tolerance_um) {
        for (const auto& t : a.tests)
            for (const auto& run : t.result.runs)
                if (run.circularity_um > *o.tolerance_um) return kExitFailure;
    }
    return kExitOk;
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
