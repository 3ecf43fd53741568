// SPDX-License-Identifier: MIT
#include "ballbar/workflow/identify.hpp"

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "ballbar/storage/readings.hpp"
#include "ballbar/storage/readings_file.hpp"
#include "ballbar/workflow/error.hpp"

namespace ballbar::workflow {

namespace ba = ballbar::analysis;
namespace bs = ballbar::storage;
using nlohmann::json;

bool looks_like_session_key(std::string_view arg) {
    return !arg.empty() && std::all_of(arg.begin(), arg.end(), [](char c) {
        return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F') || c == '-';
    });
}

ReadingInputs read_inputs(std::span<const std::string> inputs, const StoreOpener& sessions) {
    ReadingInputs in;
    for (const std::string& arg : inputs) {
        std::error_code ec;
        // Anything at that path is a file to read (fileio says when it is a directory or a FIFO).
        if (std::filesystem::exists(std::filesystem::symlink_status(arg, ec))) {
            try {
                in.sets.push_back(bs::read_readings_file(arg).set);
            } catch (const bs::ReadingsFileError& e) {
                throw Error(ErrorCategory::bad_input, arg + ": " + e.what());
            }
            in.names.push_back(arg);
            continue;
        }
        if (!looks_like_session_key(arg)) throw Error(ErrorCategory::bad_input, "no such file: " + arg);
        bs::Store& store = sessions();
        std::int64_t id = 0;
        try {
            id = store.find_session(arg);
        } catch (const bs::StorageError& e) {
            throw Error(ErrorCategory::bad_input,
                        "'" + arg + "' is neither a readings file nor a session: " + e.what());
        }
        in.sets.push_back(bs::load_readings(store, id));
        if (in.sets.back().readings.empty())
            throw Error(ErrorCategory::bad_input, "session " + std::to_string(id) + " has no readings");
        in.sessions.push_back(id);
        in.names.push_back("session " + std::to_string(id));
    }
    return in;
}

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

namespace {

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

}  // namespace

IdentifyResult identify(ReadingInputs inputs, const IdentifyOptions& options, const StoreOpener& for_writing) {
    ba::ReadingSet readings;
    try {
        readings = ba::merge_readings(std::move(inputs.sets));
    } catch (const ba::AnalysisError& e) {
        throw Error(ErrorCategory::bad_input, e.what());
    }
    ba::FitOptions fo;
    fo.free_params = options.free_params.empty() ? ba::rotary_params_for(readings.machine.type) : options.free_params;
    IdentifyResult r;
    try {
        r.fit = ba::fit_error_model(readings, fo);
    } catch (const ba::AnalysisError& e) {
        // Valid readings that cannot support the fit (too few for the unknowns): the operation failed.
        throw Error(ErrorCategory::failed, std::string("identification failed: ") + e.what());
    }
    r.model = fitted_model(readings.machine, r.fit);
    const std::string model = bs::model_to_json(r.model);
    json payload = summary_json(r.fit);
    payload["model"] = json::parse(model);
    r.payload_json = payload.dump();
    if (options.store_model && r.fit.converged) {
        bs::Store& st = for_writing();
        const std::string name = !options.model_name.empty()      ? options.model_name
                                 : !readings.machine.name.empty() ? readings.machine.name
                                                                  : std::string(ba::to_string(readings.machine.type));
        r.stored = st.save_model(name, model, inputs.sessions, std::nullopt, "ballbar identify");
        for (std::int64_t s : inputs.sessions)
            st.add_result(s, "identification", r.payload_json, r.stored->id, "ballbar identify/1");
    }
    return r;
}

}  // namespace ballbar::workflow
