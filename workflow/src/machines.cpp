// SPDX-License-Identifier: MIT
#include "ballbar/workflow/machines.hpp"

#include <nlohmann/json.hpp>

#include "ballbar/storage/machine_json.hpp"
#include "ballbar/workflow/error.hpp"

namespace ballbar::workflow {

namespace acq = ballbar::acquisition;

namespace {

/// The machine file of `change` with its tolerances applied, over `base` when it gives none.
acq::MachineFile merged(const MachineChange& change, const std::optional<acq::MachineFile>& base) {
    acq::MachineFile m;
    if (!change.machine_file_text.empty()) {
        try {
            m = acq::parse_machine_file(change.machine_file_text);
        } catch (const acq::PlanError& e) {
            throw Error(ErrorCategory::bad_input, change.machine_file_name + ": " + e.what());
        }
    } else if (base) {
        m = *base;
    } else {
        throw Error(ErrorCategory::bad_input, "a machine is registered with its machine file (--machine FILE)");
    }
    if (change.tolerances.location_um) m.tolerances.location_um = change.tolerances.location_um;
    if (change.tolerances.angle_arcsec) m.tolerances.angle_arcsec = change.tolerances.angle_arcsec;
    if (change.tolerances.circularity_um) m.tolerances.circularity_um = change.tolerances.circularity_um;
    return m;
}

nlohmann::json opt(const std::optional<double>& v) {
    return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}
nlohmann::json text_or_null(const std::string& s) {
    return s.empty() ? nlohmann::json(nullptr) : nlohmann::json(s);
}

}  // namespace

acq::MachineFile machine_file_of(const MachineChange& change) {
    return merged(change, std::nullopt);
}

storage::MachineEntry add_machine(storage::Store& store, const std::string& asset_id, const MachineChange& change) {
    if (asset_id.empty() || asset_id.find_first_of("\n\r\t") != std::string::npos)
        throw Error(ErrorCategory::bad_input, "an asset id is one line of text, not empty");
    for (const auto& m : store.machines())
        if (m.asset_id == asset_id)
            throw Error(
                ErrorCategory::bad_input,
                "machine " + asset_id + " is registered already (ballbar machines edit " + asset_id + " changes it)");
    acq::MachineFile file = machine_file_of(change);
    file.geometry.name = change.name.value_or(file.geometry.name);
    storage::NewMachine n;
    n.asset_id = asset_id;
    n.name = file.geometry.name;
    n.location = change.location.value_or("");
    n.geometry = file.geometry;
    n.machine_file_json = acq::write_machine_file(file);
    return store.register_machine(n);
}

storage::MachineEntry edit_machine(storage::Store& store, const std::string& asset_id, const MachineChange& change) {
    const storage::MachineEntry before = store.machine(asset_id);
    storage::MachineEdit e;
    e.name = change.name;
    e.location = change.location;
    const bool file_changes = !change.machine_file_text.empty() || change.tolerances.any();
    if (file_changes) {
        acq::MachineFile file = merged(change, registered_machine_file(store, asset_id));
        file.geometry.name = change.name.value_or(before.name);
        if (storage::machine_to_json(file.geometry) != before.geometry_json && before.session_count > 0)
            throw Error(ErrorCategory::bad_input,
                        "machine " + asset_id + " has " + std::to_string(before.session_count) +
                            " session(s) measured with its geometry, which the new machine file changes: a machine "
                            "with another geometry is registered as a new one (ballbar machines add)");
        e.geometry = file.geometry;
        e.machine_file_json = acq::write_machine_file(file);
    } else if (change.name) {
        auto g = storage::machine_from_json(before.geometry_json);
        g.name = *change.name;
        e.geometry = g;
    }
    return store.edit_machine(asset_id, e);
}

acq::MachineFile registered_machine_file(storage::Store& store, const std::string& asset_id) {
    const storage::MachineEntry m = store.machine(asset_id);
    acq::MachineFile file;
    try {
        file = acq::parse_machine_file(m.machine_file_json);
    } catch (const acq::PlanError& e) {
        throw Error(ErrorCategory::failed, "machine " + asset_id + "'s stored machine file is unreadable: " + e.what());
    }
    file.geometry = storage::machine_from_json(m.geometry_json);
    file.geometry.name = m.name;
    return file;
}

namespace {

nlohmann::json machine_object(const storage::MachineEntry& m) {
    nlohmann::json j;
    j["asset_id"] = text_or_null(m.asset_id);
    j["uuid"] = m.uuid;
    j["name"] = m.name;
    j["type"] = std::string(analysis::to_string(m.type));
    j["location"] = text_or_null(m.location);
    j["registered"] = !m.asset_id.empty();
    j["registered_at"] = text_or_null(m.registered_at);
    j["updated_at"] = text_or_null(m.updated_at);
    j["sessions"] = m.session_count;
    nlohmann::json tol = {{"location_um", nullptr}, {"angle_arcsec", nullptr}, {"circularity_um", nullptr}};
    nlohmann::json file = nullptr;
    if (!m.machine_file_json.empty()) {
        try {
            const acq::MachineFile f = acq::parse_machine_file(m.machine_file_json);
            tol = {{"location_um", opt(f.tolerances.location_um)},
                   {"angle_arcsec", opt(f.tolerances.angle_arcsec)},
                   {"circularity_um", opt(f.tolerances.circularity_um)}};
            file = nlohmann::json::parse(m.machine_file_json);
        } catch (const std::exception&) {
            file = nullptr;  // unreadable: `machines show` says so through registered_machine_file
        }
    }
    j["tolerances"] = tol;
    j["machine_file"] = file;
    return j;
}

}  // namespace

std::string machine_json(const storage::MachineEntry& machine) {
    return machine_object(machine).dump(2);
}

std::string machines_json(const std::vector<storage::MachineEntry>& machines) {
    nlohmann::json a = nlohmann::json::array();
    for (const auto& m : machines) a.push_back(machine_object(m));
    return a.dump(2);
}

}  // namespace ballbar::workflow
