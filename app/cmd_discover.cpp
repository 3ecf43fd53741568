// SPDX-License-Identifier: MIT
// `ballbar discover SESSION|FILE... [--model MODEL] [--json]`: the discovery workflow (docs/discovery.md)
// on the readings of stored sessions and/or readings files. Prints a table (or, with --json, the
// result as JSON); with sessions among the inputs, stores the result with each session and the
// extended model, one version per step, in the models table.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ballbar/analysis/discovery.hpp"
#include "ballbar/analysis/effects.hpp"
#include "ballbar/analysis/identify.hpp"
#include "ballbar/storage/readings.hpp"
#include "ballbar/storage/readings_file.hpp"
#include "ballbar/storage/sqlite.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/version.hpp"
#include "command.hpp"

namespace ballbar::app {
namespace {

namespace ba = ballbar::analysis;
using json = nlohmann::ordered_json;

struct DiscoverOptions {
    std::vector<std::string> inputs;
    std::string model;
    std::string save_model;
    bool json = false;
};

struct Inputs {
    std::vector<ba::ReadingSet> sets;
    std::vector<std::int64_t> sessions;
    std::vector<std::string> names;
};

/// Readings files by path; anything else is a session (id or uuid prefix) of the database.
Inputs load_inputs(const DiscoverOptions& o, const Globals& globals, std::unique_ptr<storage::Store>& store) {
    Inputs in;
    for (const std::string& arg : o.inputs) {
        std::error_code ec;
        if (std::filesystem::is_regular_file(arg, ec)) {
            try {
                in.sets.push_back(storage::read_readings_file(arg).set);
            } catch (const storage::ReadingsFileError& e) {
                throw CliError(kExitUsage, arg + ": " + e.what());
            }
            in.names.push_back(arg);
            continue;
        }
        if (!store) store = std::make_unique<storage::Store>(resolve_db_path(globals));
        std::int64_t id = 0;
        try {
            id = store->find_session(arg);
        } catch (const storage::StorageError& e) {
            throw CliError(kExitUsage, "'" + arg + "' is neither a readings file nor a session: " + e.what());
        }
        in.sets.push_back(storage::load_readings(*store, id));
        if (in.sets.back().readings.empty())
            throw CliError(kExitUsage, "session " + std::to_string(id) + " has no readings");
        in.sessions.push_back(id);
        in.names.push_back("session " + std::to_string(id));
    }
    return in;
}

std::vector<std::string> param_names(const std::vector<ba::Param>& params) {
    std::vector<std::string> out;
    for (ba::Param p : params) out.emplace_back(ba::param_info(p).name);
    return out;
}

/// The JSON shape (docs/discovery.md).
json result_json(const ba::DiscoveryResult& r) {
    json steps = json::array();
    for (const ba::DiscoveryStep& st : r.steps)
        steps.push_back({{"effect", std::string(st.effect->id)},
                         {"iso", std::string(st.effect->iso)},
                         {"estimate", st.estimate},
                         {"unit", std::string(ba::to_string(st.effect->unit()))},
                         {"stderr", st.std_error},
                         {"rms_before_um", st.rms_before_mm * 1e3},
                         {"rms_after_um", st.rms_after_mm * 1e3},
                         {"criterion", st.criterion},
                         {"value", st.value},
                         {"explained_by", std::string(ba::to_string(st.explained_by, r.type))}});
    return {{"base_model", param_names(r.base_model)},
            {"rms_initial_um", r.rms_initial_mm * 1e3},
            {"steps", steps},
            {"rms_final_um", r.rms_final_mm * 1e3},
            {"confounded", r.confounded},
            {"unidentifiable", r.unidentifiable}};
}

json params_json(const std::vector<ba::Param>& model, const ba::ErrorParams& values) {
    json p = json::object();
    for (ba::Param q : model) p[std::string(ba::param_info(q).name)] = values[q];
    return p;
}

/// What the stored result holds beyond the printed JSON: the criterion and the residual analysis.
json details_json(const ba::DiscoveryResult& r, const std::vector<std::string>& inputs) {
    auto trends = [&r](const ba::ResidualAnalysis& a) {
        json t = json::array();
        for (const auto& v : a.trends)
            t.push_back({{"variable", std::string(ba::to_string(v.variable, r.type))},
                         {"r2", v.r2},
                         {"bin_centre", v.bin_centre},
                         {"bin_mean_um", [&v] {
                              std::vector<double> um;
                              for (double m : v.bin_mean_mm) um.push_back(m * 1e3);
                              return um;
                          }()}});
        return t;
    };
    auto um = [](const std::vector<double>& mm) {
        std::vector<double> out;
        for (double m : mm) out.push_back(m * 1e3);
        return out;
    };
    json step_trends = json::array();  // each step's own before/after, against its variable
    for (const ba::DiscoveryStep& st : r.steps)
        step_trends.push_back({{"variable", std::string(ba::to_string(st.explained_by, r.type))},
                               {"bin_centre", st.trend_before.bin_centre},
                               {"before_um", um(st.trend_before.bin_mean_mm)},
                               {"after_um", um(st.trend_after.bin_mean_mm)}});
    return {{"inputs", inputs},
            {"criterion", r.criterion_text},
            {"final_model", params_json(r.final_model, r.final_fit.model)},
            {"residuals_initial", trends(r.initial_residuals)},
            {"residuals_final", trends(r.final_residuals)},
            {"step_trends", step_trends}};
}

/// Stores the result with every input session and the extended model, one version per step.
void store_result(storage::Store& store, const Inputs& in, const ba::DiscoveryResult& r, const std::string& name) {
    storage::ModelRecord rec = store.save_model(name, json{{"params", params_json(r.base_model, r.base_fit)}}.dump(),
                                                in.sessions, std::nullopt, "discovery: base model");
    std::vector<ba::Param> model = r.base_model;
    for (const ba::DiscoveryStep& st : r.steps) {
        model.push_back(st.effect->param);
        char note[200];
        std::snprintf(note, sizeof note, "discovery: added %s%s%s, RMS %.3f -> %.3f um",
                      std::string(st.effect->id).c_str(), st.effect->iso.empty() ? "" : " ",
                      std::string(st.effect->iso).c_str(), st.rms_before_mm * 1e3, st.rms_after_mm * 1e3);
        rec = store.save_model(
            name, json{{"params", params_json(model, st.model_after)}, {"added", std::string(st.effect->id)}}.dump(),
            in.sessions, rec.id, note);
    }
    json payload = result_json(r);
    payload["details"] = details_json(r, in.names);
    payload["model"] = {{"name", name}, {"id", rec.id}, {"version", rec.version}};
    for (std::int64_t s : in.sessions)
        store.add_result(s, "discovery", payload.dump(), rec.id, std::string("ballbar ") + kVersion + " discovery/1");
}

std::string format_value(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
}

void print_table(const ba::DiscoveryResult& r, const ba::ReadingSet& set, const Inputs& in) {
    std::printf("discovery: %s machine%s%s, %zu readings from %zu input(s)\n",
                std::string(ba::to_string(r.type)).c_str(), set.machine.name.empty() ? "" : " ",
                set.machine.name.c_str(), set.readings.size(), in.names.size());
    std::printf("base model:");
    for (const auto& n : param_names(r.base_model)) std::printf(" %s", n.c_str());
    std::printf(" + socket offsets\n");
    std::printf("initial residual RMS %.3f um (best explained by %s)\n\n", r.rms_initial_mm * 1e3,
                std::string(ba::to_string(r.initial_residuals.best, r.type)).c_str());
    if (r.steps.empty()) {
        std::printf("no effect passes the criterion: what is left is noise at this model\n");
    } else {
        std::printf("%-4s %-24s %-5s %14s %10s %-6s %21s %10s  %s\n", "step", "effect", "ISO", "estimate", "std",
                    "unit", "RMS before -> after", "F", "explained by");
        int i = 1;
        for (const ba::DiscoveryStep& st : r.steps)
            std::printf("%-4d %-24s %-5s %14s %10s %-6s %9.3f -> %6.3f um %10.1f  %s\n", i++,
                        std::string(st.effect->id).c_str(), std::string(st.effect->iso).c_str(),
                        format_value(st.estimate).c_str(), format_value(st.std_error).c_str(),
                        std::string(ba::to_string(st.effect->unit())).c_str(), st.rms_before_mm * 1e3,
                        st.rms_after_mm * 1e3, st.value, std::string(ba::to_string(st.explained_by, r.type)).c_str());
    }
    std::printf("\nfinal residual RMS %.3f um\n", r.rms_final_mm * 1e3);
    for (const auto& g : r.confounded) {
        std::printf("confounded (the readings cannot tell these apart):");
        for (const auto& n : g) std::printf(" %s", n.c_str());
        std::printf("\n");
    }
    if (!r.unidentifiable.empty()) {
        std::printf("not determined by these readings (left out):");
        for (const auto& n : r.unidentifiable) std::printf(" %s", n.c_str());
        std::printf("\n");
    }
    std::printf("criterion: %s\n", r.criterion_text.c_str());
}

int run_discover(const DiscoverOptions& o, const Globals& globals) {
    std::unique_ptr<storage::Store> store;
    const Inputs in = load_inputs(o, globals, store);
    ba::ReadingSet set;
    try {
        set = in.sets.size() == 1 ? in.sets.front() : ba::merge_readings(in.sets);
    } catch (const ba::AnalysisError& e) {
        throw CliError(kExitUsage, std::string("cannot combine the inputs: ") + e.what());
    }
    ba::DiscoveryOptions opt;
    if (!o.model.empty()) {
        try {
            opt.base_model = ba::parse_model(o.model, set.machine.type);
        } catch (const ba::AnalysisError& e) {
            throw CliError(kExitUsage, std::string("--model: ") + e.what());
        }
    }
    ba::DiscoveryResult r;
    try {
        r = ba::discover(set, opt);
    } catch (const ba::AnalysisError& e) {
        throw CliError(kExitFailure, std::string("discovery failed: ") + e.what());
    }
    if (store && !in.sessions.empty()) {
        const std::string name = !o.save_model.empty()
                                     ? o.save_model
                                     : (set.machine.name.empty() ? "machine" : set.machine.name) + "-discovered";
        store_result(*store, in, r, name);
    }
    if (o.json)
        std::cout << result_json(r).dump() << std::endl;
    else
        print_table(r, set, in);
    return kExitOk;
}

}  // namespace
}  // namespace ballbar::app

BALLBAR_COMMAND(discover) {
    using namespace ballbar::app;
    auto opts = std::make_shared<DiscoverOptions>();
    auto* sub = root.add_subcommand(
        "discover",
        "Find where the model and the readings disagree, name the missing effects, refit (docs/discovery.md)");
    sub->add_option("inputs", opts->inputs, "Readings files (ballbar-readings/1) and/or session ids")->required();
    sub->add_option("--model", opts->model,
                    "Model to start from: comma-separated parameters or effect ids, 'base' for the rotary location "
                    "errors and zero offsets (default)");
    sub->add_option("--save-model", opts->save_model,
                    "Name of the extended model stored with the sessions (default <machine>-discovered)");
    sub->add_flag("--json", opts->json, "Print the result as JSON");
    sub->callback([opts, &globals] { globals.action = [opts, &globals] { return run_discover(*opts, globals); }; });
}
