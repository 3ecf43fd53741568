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
#include "ballbar/storage/readings.hpp"
#include "ballbar/storage/readings_file.hpp"
#include "ballbar/storage/store.hpp"
#include "command.hpp"
#include "figures.hpp"

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

/// The model the fit made, as it is stored (ballbar-model/1).
bs::ErrorModel fitted_model(const ba::MachineGeometry& machine, const ba::FitSummary& fit) {
    bs::ErrorModel m;
    m.machine = machine;
    for (const auto& e : fit.estimates) {
        if (!e.param) continue;  // a socket's offset: the sockets below
        if (e.observable)
            m.params.push_back({*e.param, e.estimate, e.std});
        else
            m.unobservable.push_back(*e.param);
    }
    for (const auto& s : fit.sockets) m.sockets.push_back({s.nominal_mm, s.offset_mm});
    m.residual_rms_um = fit.residual_rms_mm * 1e3;
    m.readings = fit.readings;
    m.converged = fit.converged;
    return m;
}

json summary_json(const ba::FitSummary& fit) {
    json j;
    j["converged"] = fit.converged;
    j["iterations"] = fit.iterations;
    j["message"] = fit.message;
    j["readings"] = fit.readings;
    j["degrees_of_freedom"] = fit.degrees_of_freedom;
    j["residual_rms_um"] = fit.residual_rms_mm * 1e3;
    j["residual_sigma_um"] = fit.residual_sigma_mm * 1e3;
    j["noise_floor_um"] = fit.noise_floor_mm * 1e3;
    j["uncertainty_from_noise_floor"] = fit.uncertainty_from_floor;
    j["initial_rms_um"] = fit.initial_rms_mm * 1e3;
    j["estimates"] = json::array();
    for (const auto& e : fit.estimates) {
        json x{{"name", e.name},
               {"estimate", e.estimate},
               {"std", e.std},
               {"sensitivity", e.sensitivity},
               {"independence", e.independence},
               {"observable", e.observable}};
        if (e.param)
            x["unit"] = std::string(ba::to_string(ba::param_info(*e.param).unit));
        else
            x["unit"] = "mm";
        j["estimates"].push_back(x);
    }
    j["correlation"] = json::array();
    for (Eigen::Index r = 0; r < fit.correlation.rows(); ++r) {
        json row = json::array();
        for (Eigen::Index c = 0; c < fit.correlation.cols(); ++c) row.push_back(fit.correlation(r, c));
        j["correlation"].push_back(row);
    }
    j["correlation_names"] = json::array();
    for (std::size_t i : fit.fitted) j["correlation_names"].push_back(fit.estimates[i].name);
    return j;
}

int run_identify(const IdentifyArgs& args, const Globals& globals) {
    std::vector<ba::ReadingSet> sets;
    std::vector<std::int64_t> sessions;
    std::unique_ptr<bs::Store> store;
    // Sessions are read from an existing database only (a mistyped --db is an error, not a new
    // file); storing the model from readings files alone may create it.
    auto open_store = [&](bool create) -> bs::Store& {
        if (!store) store = std::make_unique<bs::Store>(create ? resolve_db_path(globals) : existing_db_path(globals));
        return *store;
    };
    for (const std::string& in : args.inputs) {
        std::error_code ec;
        if (!std::filesystem::exists(in, ec) && !looks_like_session_key(in))
            throw Error(ErrorCategory::bad_input, "no such file: " + in);
        // Anything at that path is a file to read (fileio says when it is a directory or a FIFO).
        if (std::filesystem::exists(std::filesystem::symlink_status(in, ec))) {
            try {
                sets.push_back(bs::read_readings_file(in).set);
            } catch (const bs::ReadingsFileError& e) {
                throw Error(ErrorCategory::bad_input, in + ": " + e.what());
            }
        } else {
            bs::Store& st = open_store(false);
            std::int64_t id = 0;
            try {
                id = st.find_session(in);
            } catch (const bs::StorageError& e) {
                throw Error(ErrorCategory::bad_input,
                            "'" + in + "' is neither a readings file nor a session: " + e.what());
            }
            sets.push_back(bs::load_readings(st, id));
            sessions.push_back(id);
        }
    }
    ba::ReadingSet readings;
    try {
        readings = ba::merge_readings(std::move(sets));
    } catch (const ba::AnalysisError& e) {
        throw Error(ErrorCategory::bad_input, e.what());
    }
    ba::FitOptions fo;
    fo.free_params = parse_params(args.params, readings.machine.type);
    ba::FitSummary fit;
    try {
        fit = ba::fit_error_model(readings, fo);
    } catch (const ba::AnalysisError& e) {
        // Valid readings that cannot support the fit (too few for the unknowns): the operation failed,
        // as in `discover`.
        throw Error(ErrorCategory::failed, std::string("identification failed: ") + e.what());
    }

    json out = summary_json(fit);
    const std::string model = bs::model_to_json(fitted_model(readings.machine, fit));
    out["model"] = json::parse(model);
    if (!args.no_store && fit.converged) {
        bs::Store& st = open_store(true);
        const std::string name = !args.name.empty()               ? args.name
                                 : !readings.machine.name.empty() ? readings.machine.name
                                                                  : std::string(ba::to_string(readings.machine.type));
        const bs::ModelRecord rec = st.save_model(name, model, sessions, std::nullopt, "ballbar identify");
        for (std::int64_t s : sessions) st.add_result(s, "identification", out.dump(), rec.id, "ballbar identify/1");
        out["model_id"] = rec.id;
        out["model_name"] = rec.name;
        out["model_version"] = rec.version;
    }
    if (args.json) {
        std::cout << out.dump(2) << '\n';
    } else {
        std::cout << fit_report(fit);  // units and uncertainties (figures.hpp)
        if (out.contains("model_id"))
            std::cout << "stored as model " << out["model_id"] << " (" << out["model_name"].get<std::string>()
                      << " version " << out["model_version"] << ")\n";
    }
    return fit.converged ? kExitOk : kExitFailure;
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
    sub->footer(
        "Parameters the data cannot determine are reported unobservable and held at 0.\n"
        "See docs/identification.md.");
    sub->callback([&globals, args] { globals.action = [&globals, args]() { return run_identify(*args, globals); }; });
}
