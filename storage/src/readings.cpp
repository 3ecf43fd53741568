// SPDX-License-Identifier: MIT
#include "ballbar/storage/readings.hpp"

#include <algorithm>
#include <cmath>
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

namespace {

NewSession imported_session(const analysis::MachineGeometry& machine, const ReadingsMetadata& metadata) {
    NewSession ns;
    ns.machine = machine;
    ns.instrument = metadata.instrument;
    ns.source = SessionSource::imported;
    ns.operator_name = metadata.operator_name;
    ns.procedure = "import";
    ns.notes = metadata.notes;
    ns.started_at = metadata.started_at;
    if (!metadata.extra.empty()) {
        nlohmann::ordered_json extra = nlohmann::ordered_json::object();
        for (const auto& [key, value] : metadata.extra) extra[key] = nlohmann::ordered_json::parse(value);
        ns.metadata_json = extra.dump();
    }
    return ns;
}

}  // namespace

ImportedReadings import_readings_stream(Store& store, ReadingsStream& stream, std::string_view origin,
                                        std::size_t batch) {
    ImportedReadings out;
    out.warnings = stream.warnings();
    Transaction tx(store.db());
    out.session = store.create_session(imported_session(stream.machine(), stream.metadata()));
    std::vector<PointRecord> points;
    points.reserve(batch);
    PointRecord p;
    std::optional<NominalMismatch> mismatch;
    while (stream.next(p.reading, p.nominal_mm, mismatch)) {
        if (mismatch) {
            if (out.first_mismatch_lines.size() < 10) out.first_mismatch_lines.push_back(mismatch->line);
            ++out.nominal_mismatches;
            out.worst_mismatch_mm =
                std::max(out.worst_mismatch_mm, std::abs(mismatch->file_nominal_mm - mismatch->computed_nominal_mm));
        }
        points.push_back(p);
        if (points.size() == batch) {
            store.add_points(out.session, points);
            points.clear();
        }
    }
    store.add_points(out.session, points);
    out.readings = stream.count();
    store.transition(out.session, SessionState::completed,
                     origin.empty() ? std::string("import") : "import: " + std::string(origin));
    tx.commit();
    return out;
}

std::int64_t import_readings(Store& store, const ReadingsFile& file, std::string_view origin) {
    const NewSession ns = imported_session(file.set.machine, file.metadata);
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
