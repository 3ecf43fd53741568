// SPDX-License-Identifier: MIT
#include "ballbar/workflow/discover.hpp"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <span>

#include "ballbar/analysis/effects.hpp"
#include "ballbar/storage/discovery_codec.hpp"
#include "ballbar/storage/model_codec.hpp"
#include "ballbar/workflow/error.hpp"

namespace ballbar::workflow {
namespace {

namespace ba = ballbar::analysis;
using ojson = nlohmann::ordered_json;

/// A version of the model as it is stored (ballbar-model/1): the parameters `model` names, their values.
std::string stored_model(const ba::ReadingSet& readings, const std::vector<ba::Param>& model,
                         const ba::ErrorParams& values, std::span<const ba::LearnedTerm> learned = {},
                         std::string added = {}) {
    storage::ErrorModel m;
    m.machine = readings.machine;
    ba::PoseRange measured;  // where it was measured: `compensate` says where a program leaves it
    for (const auto& r : readings.readings) measured.add(r.pose);
    if (!measured.empty) m.measured_poses = measured;
    for (ba::Param q : model) m.params.push_back({q, values[q], std::nullopt});
    m.empirical.assign(learned.begin(), learned.end());
    m.added = std::move(added);
    return storage::model_to_json(m);
}

/// Stores the result with every input session and the extended model, one version per step; the last.
storage::ModelRecord store_result(storage::Store& store, const ReadingInputs& in, const ba::DiscoveryResult& r,
                                  const std::string& name, const ba::ReadingSet& readings) {
    storage::ModelRecord rec = store.save_model(name, stored_model(readings, r.base_model, r.base_fit), in.sessions,
                                                std::nullopt, "discovery: base model");
    std::vector<ba::Param> model = r.base_model;
    for (const ba::DiscoveryStep& st : r.steps) {
        model.push_back(st.effect->param);
        char note[200];
        std::snprintf(note, sizeof note, "discovery: added %s%s%s, RMS %.3f -> %.3f µm",
                      std::string(st.effect->id).c_str(), st.effect->iso.empty() ? "" : " ",
                      std::string(st.effect->iso).c_str(), st.rms_before_mm * 1e3, st.rms_after_mm * 1e3);
        rec = store.save_model(name, stored_model(readings, model, st.model_after, {}, std::string(st.effect->id)),
                               in.sessions, rec.id, note);
    }
    std::vector<ba::LearnedTerm> learned;
    for (const ba::EmpiricalStep& st : r.learned) {
        learned.insert(learned.end(), st.terms.begin(), st.terms.end());
        char note[300];
        std::snprintf(note, sizeof note, "discovery: learned %s (%s), RMS %.3f -> %.3f µm", st.family.c_str(),
                      st.description.c_str(), st.rms_before_mm * 1e3, st.rms_after_mm * 1e3);
        rec = store.save_model(name, stored_model(readings, r.final_model, r.final_fit.model, learned, st.family),
                               in.sessions, rec.id, note);
    }
    const std::string payload =
        storage::discovery_to_json(r, storage::DiscoveryStored{in.names, name, rec.id, rec.version});
    for (std::int64_t s : in.sessions)
        store.add_result(s, std::string(storage::kDiscoveryResultKind), payload, rec.id,
                         std::string("ballbar ") + BALLBAR_VERSION + " discovery/1");
    return rec;
}

}  // namespace

std::string discovery_json(const ba::DiscoveryResult& result) {
    return storage::discovery_to_json(result);
}

DiscoverResult discover(ReadingInputs in, const DiscoverOptions& o, const StoreOpener& for_writing) {
    DiscoverResult out;
    out.input_names = in.names;
    try {
        out.readings = ba::merge_readings(std::move(in.sets));  // moved: the readings are held once
    } catch (const ba::AnalysisError& e) {
        throw Error(ErrorCategory::bad_input, std::string("cannot combine the inputs: ") + e.what());
    }
    ba::DiscoveryOptions opt;
    if (o.noise_um) {
        if (!(*o.noise_um > 0) || !std::isfinite(*o.noise_um))
            throw Error(ErrorCategory::bad_input, "--noise-um: must be a positive number of micrometres");
        opt.noise_mm = *o.noise_um * 1e-3;
    }
    opt.resolution_mm = in.resolution_mm;
    if (!o.model.empty()) {
        try {
            opt.base_model = ba::parse_model(o.model, out.readings.machine.type);
        } catch (const ba::AnalysisError& e) {
            throw Error(ErrorCategory::bad_input, std::string("--model: ") + e.what());
        }
    }
    try {
        out.result = ba::discover(out.readings, opt);
    } catch (const ba::AnalysisError& e) {
        throw Error(ErrorCategory::failed, std::string("discovery failed: ") + e.what());
    }
    if (for_writing && !in.sessions.empty()) {
        const ba::MachineGeometry& machine = out.readings.machine;
        const std::string name =
            !o.save_model.empty() ? o.save_model : (machine.name.empty() ? "machine" : machine.name) + "-discovered";
        out.stored = store_result(for_writing(), in, out.result, name, out.readings);
    }
    return out;
}

}  // namespace ballbar::workflow
