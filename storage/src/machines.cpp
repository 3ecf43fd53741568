// SPDX-License-Identifier: MIT
// The machine registry and the station's id (schema v7; docs/fleet.md).
#include <string>

#include "ballbar/storage/machine_json.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::storage {

namespace {

constexpr const char* kMachineSelect =
    "SELECT m.id, m.uuid, coalesce(m.asset_id, ''), m.name, m.type, m.geometry_json, m.location, "
    "m.machine_file_json, coalesce(m.registered_at, ''), coalesce(m.updated_at, ''), "
    "(SELECT count(*) FROM sessions s WHERE s.machine_id = m.id) FROM machines m ";

MachineEntry read_machine(const Statement& st) {
    MachineEntry m;
    m.id = st.column_int(0);
    m.uuid = st.column_text(1);
    m.asset_id = st.column_text(2);
    m.name = st.column_text(3);
    m.type = analysis::parse_machine_type(st.column_text(4)).value_or(analysis::MachineType::TTTRR);
    m.geometry_json = st.column_text(5);
    m.location = st.column_text(6);
    m.machine_file_json = st.column_text(7);
    m.registered_at = st.column_text(8);
    m.updated_at = st.column_text(9);
    m.session_count = st.column_int(10);
    return m;
}

}  // namespace

MachineEntry Store::register_machine(const NewMachine& n) {
    if (n.asset_id.empty()) throw StorageError(StorageError::Kind::invalid, "a machine needs an asset id");
    Transaction tx(db_);
    auto taken = db_.prepare("SELECT 1 FROM machines WHERE asset_id = ?");
    taken.bind(1, n.asset_id);
    if (taken.step())
        throw StorageError(
            StorageError::Kind::invalid,
            "machine " + n.asset_id + " is registered already (ballbar machines edit " + n.asset_id + ")");
    auto ins = db_.prepare(
        "INSERT INTO machines(uuid, asset_id, name, type, geometry_json, location, machine_file_json, registered_at) "
        "VALUES (?, ?, ?, ?, ?, ?, ?, ?)");
    ins.bind(1, new_uuid()).bind(2, n.asset_id).bind(3, n.name).bind(4, analysis::to_string(n.geometry.type));
    ins.bind(5, machine_to_json(n.geometry)).bind(6, n.location).bind(7, n.machine_file_json).bind(8, now_iso8601());
    ins.run();
    tx.commit();
    return machine(n.asset_id);
}

std::vector<MachineEntry> Store::machines() {
    std::vector<MachineEntry> out;
    if (schema_version_ < 7) return out;  // a file of an earlier version opened read-only: no registry
    auto st = db_.prepare(std::string(kMachineSelect) + "ORDER BY m.asset_id IS NULL, m.asset_id, m.id");
    while (st.step()) out.push_back(read_machine(st));
    return out;
}

MachineEntry Store::machine(std::string_view asset_id) {
    if (schema_version_ >= 7) {
        auto st = db_.prepare(std::string(kMachineSelect) + "WHERE m.asset_id = ?");
        st.bind(1, asset_id);
        if (st.step()) return read_machine(st);
    }
    std::string known;
    for (const MachineEntry& m : machines())
        if (!m.asset_id.empty()) known += (known.empty() ? "" : ", ") + m.asset_id;
    throw StorageError(
        StorageError::Kind::not_found,
        "no machine \"" + std::string(asset_id) + "\" in the registry (" +
            (known.empty() ? std::string("none registered: ballbar machines add") : "there are " + known) + ")");
}

MachineEntry Store::edit_machine(std::string_view asset_id, const MachineEdit& e) {
    Transaction tx(db_);
    const MachineEntry m = machine(asset_id);
    if (e.geometry) {
        const std::string json = machine_to_json(*e.geometry);
        if (json != m.geometry_json && m.session_count > 0)
            throw StorageError(StorageError::Kind::invalid,
                               "machine " + m.asset_id + " has " + std::to_string(m.session_count) +
                                   " session(s) measured with its geometry: a new geometry is a new machine "
                                   "(ballbar machines add), or the same one rebuilt under a new asset id");
        auto up = db_.prepare("UPDATE machines SET geometry_json = ?, type = ? WHERE id = ?");
        up.bind(1, json).bind(2, analysis::to_string(e.geometry->type)).bind(3, m.id).run();
    }
    auto up = db_.prepare(
        "UPDATE machines SET name = coalesce(?, name), location = coalesce(?, location), "
        "machine_file_json = coalesce(?, machine_file_json), updated_at = ? WHERE id = ?");
    up.bind(1, e.name).bind(2, e.location).bind(3, e.machine_file_json).bind(4, now_iso8601()).bind(5, m.id).run();
    tx.commit();
    return machine(asset_id);
}

std::string Store::station_uuid() {
    if (schema_version_ < 7) return {};
    return db_.query_text("SELECT uuid FROM station WHERE id = 1");
}

}  // namespace ballbar::storage
