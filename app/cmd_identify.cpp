// SPDX-License-Identifier: MIT
// `ballbar identify SESSION|FILE... [--json] [--params P,...] [--name NAME] [--no-store]`: identifies the
// machine's error model from the readings of one or several sessions (database ids or uuid prefixes)
// or `ballbar-readings/1` files, prints estimates, uncertainties, observability and residuals, and
// stores the model (models table, format `ballbar-model/1`, docs/identification.md) with the sessions.
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "ballbar/analysis/identify.hpp"
#include "ballbar/storage/model_codec.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/workflow/identify.hpp"
#include "command.hpp"
#include "figures.hpp"
#include "files.hpp"

namespace ballbar::app {
namespace {

namespace ba = ballbar::analysis;
namespace bs = ballbar::storage;
using nlohmann::json;

struct IdentifyArgs {
    std::vector<std::string> inputs;
    std::vector<std::string> params;
    std::string name;
    bool json = false;
    bool no_store = false;
    std::string out;  ///< --out: the model as a ballbar-model/1 file (ballbarkins' model=, compensate --model)
};

std::vector<ba::Param> parse_params(const std::vector<std::string>& names, ba::MachineType type) {
    if (names.empty()) return ba::rotary_params_for(type);
    std::vector<ba::Param> out;
    for (const std::string& n : names) {
        if (n == "all") {
            for (ba::Param p : ba::params_for(type)) out.push_back(p);
            continue;
        }
        if (n == "base" || n == "rotary") {
            for (ba::Param p : ba::rotary_params_for(type)) out.push_back(p);
            continue;
        }
        const auto p = ba::parse_param(n);
        if (!p) {
            std::string known;
            for (const auto& info : ba::all_params()) known += (known.empty() ? "" : " ") + std::string(info.name);
            throw Error(ErrorCategory::bad_input,
                        "--params: unknown parameter '" + n + "' (known: " + known + ", all, base)");
        }
        out.push_back(*p);
    }
    return out;
}

int run_identify(const IdentifyArgs& args, const Globals& globals) {
    std::unique_ptr<bs::Store> store;
    // Sessions are read from an existing database only (a mistyped --db is an error, not a new
    // file); storing the model from readings files alone may create it.
    auto opener = [&](bool create) {
        return [&store, &globals, create]() -> bs::Store& {
            if (!store)
                store = std::make_unique<bs::Store>(create ? resolve_db_path(globals) : existing_db_path(globals));
            return *store;
        };
    };
    workflow::ReadingInputs inputs = workflow::read_inputs(args.inputs, opener(false));
    workflow::IdentifyOptions io;
    io.free_params = parse_params(args.params, inputs.sets.front().machine.type);
    io.model_name = args.name;
    io.store_model = !args.no_store;
    if (!args.out.empty()) {
        try {
            fileio::check_output(args.out, "--out", database_files(globals));  // before the fit and the store
        } catch (const fileio::FileError& e) {
            throw as_error(e);
        }
    }
    const workflow::IdentifyResult r = workflow::identify(std::move(inputs), io, opener(true));
    if (!args.out.empty()) write_output(args.out, "--out", storage::model_to_json(r.model), database_files(globals));

    json out = json::parse(r.payload_json);
    // With --no-store there is no stored model: null (docs/cli.md), not absent keys.
    out["model_id"] = r.stored ? json(r.stored->id) : json(nullptr);
    out["model_name"] = r.stored ? json(r.stored->name) : json(nullptr);
    out["model_version"] = r.stored ? json(r.stored->version) : json(nullptr);
    if (args.json) {
        std::cout << out.dump(2) << '\n';
    } else {
        std::cout << fit_report(r.fit);  // units and uncertainties (figures.hpp)
        if (r.stored)
            std::cout << "stored as model " << r.stored->id << " (" << r.stored->name << " version "
                      << r.stored->version << ")\n";
    }
    return r.fit.converged ? kExitOk : kExitFailure;
}

}  // namespace
}  // namespace ballbar::app

BALLBAR_COMMAND(identify) {
    using namespace ballbar::app;
    auto args = std::make_shared<IdentifyArgs>();
    auto* sub = root.add_subcommand("identify", "Identify the machine's error model from sessions or readings files");
    sub->add_option("inputs", args->inputs, "session ids / uuid prefixes, or ballbar-readings/1 files")->required();
    sub->add_flag("--json", args->json, "print the result as JSON");
    sub->add_option("--params", args->params,
                    "parameters to estimate (ISO names, comma separated; 'base' = the rotary axes' location errors, "
                    "'all'); default base")
        ->delimiter(',');
    sub->add_option("--name", args->name, "model name in the database (default: the machine's name)");
    sub->add_flag("--no-store", args->no_store, "do not store the model");
    sub->add_option("--out", args->out,
                    "also write the model as a ballbar-model/1 file (LinuxCNC's ballbarkins model=, compensate "
                    "--model FILE)");
    sub->footer(
        "Parameters the data cannot determine are reported unobservable and held at 0.\n"
        "See docs/identification.md.");
    sub->callback([&globals, args] { globals.action = [&globals, args]() { return run_identify(*args, globals); }; });
}
