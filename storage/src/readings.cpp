// SPDX-License-Identifier: MIT
#include "ballbar/storage/readings.hpp"

#include <nlohmann/json.hpp>

#include "ballbar/analysis/kinematics.hpp"

namespace ballbar::storage {

analysis::ReadingSet load_readings(Store& store, std::int64_t session_id) {
    analysis::ReadingSet set;
    set.machine = store.session(session_id).machine;
    for (auto& p : store.points(session_id)) set.readings.push_back(std::move(p.reading));
    return set;
}

ReadingsMetadata readings_metadata(const SessionInfo& s) {
    ReadingsMetadata m;
    m.instrument = s.instrument;
    m.operator_name = s.operator_name;
    m.started_at = s.started_at;
    m.notes = s.notes;
    if (!s.metadata_json.empty()) {
        const auto j = nlohmann::ordered_json::parse(s.metadata_json, nullptr, false);
        if (j.is_object()) {
            for (const auto& [key, value] : j.items()) m.extra.emplace_back(key, value.dump());
        }
    }
    return m;
}

std::int64_t import_readings(Store& store, const ReadingsFile& file, std::string_view origin) {
    NewSession ns;
    ns.machine = file.set.machine;
    ns.instrument = file.metadata.instrument;
    ns.source = SessionSource::imported;
    ns.operator_name = file.metadata.operator_name;
    ns.procedure = "import";
    ns.notes = file.metadata.notes;
    ns.started_at = file.metadata.started_at;
    if (!file.metadata.extra.empty()) {
        nlohmann::ordered_json extra = nlohmann::ordered_json::object();
        for (const auto& [key, value] : file.metadata.extra) extra[key] = nlohmann::ordered_json::parse(value);
        ns.metadata_json = extra.dump();
    }

    Transaction tx(store.db());
    const std::int64_t id = store.create_session(ns);
    for (std::size_t i = 0; i < file.set.readings.size(); ++i) {
        PointRecord p;
        p.reading = file.set.readings[i];
        p.nominal_mm = i < file.nominal_mm.size()
                           ? file.nominal_mm[i]
                           : analysis::nominal_length(file.set.machine, p.reading.pose, p.reading.socket_mm);
        store.add_point(id, p);
    }
    store.transition(id, SessionState::completed,
                     origin.empty() ? std::string("import") : "import: " + std::string(origin));
    tx.commit();
    return id;
}

}  // namespace ballbar::storage
