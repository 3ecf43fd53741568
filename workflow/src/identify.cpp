// SPDX-License-Identifier: MIT
#include "ballbar/workflow/identify.hpp"

#include <algorithm>
#include <filesystem>

#include "ballbar/storage/identification_codec.hpp"
#include "ballbar/storage/readings.hpp"
#include "ballbar/storage/readings_file.hpp"
#include "ballbar/workflow/error.hpp"

namespace ballbar::workflow {

namespace ba = ballbar::analysis;
namespace bs = ballbar::storage;

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
        for (const auto& g : store.sample_segments(id))
            if (g.resolution_mm && *g.resolution_mm > 0)
                in.resolution_mm = std::max(in.resolution_mm.value_or(0.0), *g.resolution_mm);
    }
    return in;
}

bs::ErrorModel fitted_model(const ba::ReadingSet& readings, const ba::FitSummary& fit) {
    bs::ErrorModel m;
    m.machine = readings.machine;
    ba::PoseRange measured;
    for (const auto& r : readings.readings) measured.add(r.pose);
    if (!measured.empty) m.measured_poses = measured;
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
    r.model = fitted_model(readings, r.fit);
    const std::string model = bs::model_to_json(r.model);
    r.payload_json = bs::identification_to_json(r.fit, r.model);
    if (options.store_model && r.fit.converged) {
        bs::Store& st = for_writing();
        const std::string name = !options.model_name.empty()      ? options.model_name
                                 : !readings.machine.name.empty() ? readings.machine.name
                                                                  : std::string(ba::to_string(readings.machine.type));
        r.stored = st.save_model(name, model, inputs.sessions, std::nullopt, "ballbar identify");
        for (std::int64_t s : inputs.sessions)
            st.add_result(s, std::string(bs::kIdentificationResultKind), r.payload_json, r.stored->id,
                          "ballbar identify/1");
    }
    return r;
}

}  // namespace ballbar::workflow
