// SPDX-License-Identifier: MIT
#include "ballbar/workflow/sync.hpp"

#include <nlohmann/json.hpp>

namespace ballbar::workflow {

fleet::SyncReport sync_station(storage::Store& station, const std::string& conninfo,
                               const fleet::SyncOptions& options) {
    fleet::pg::Connection server(conninfo);
    return fleet::sync(station, server, options);
}

std::string sync_json(const fleet::SyncReport& r) {
    nlohmann::ordered_json conflicts = nlohmann::ordered_json::array();
    for (const auto& c : r.conflicts)
        conflicts.push_back({{"kind", c.kind}, {"uuid", c.uuid}, {"other_station_uuid", c.other_station}});
    nlohmann::ordered_json j = {
        {"station_uuid", r.station_uuid},
        {"server", r.server},
        {"server_schema_created", r.server_schema_before == 0},
        {"sessions_local", r.sessions_local},
        {"sessions_sent", r.sessions_sent},
        {"rows_written", r.rows()},
        {"rows",
         {{"machines", r.machines},
          {"models", r.models},
          {"sessions", r.sessions},
          {"transitions", r.transitions},
          {"points", r.points},
          {"results", r.results},
          {"segments", r.segments},
          {"gaps", r.gaps},
          {"samples", r.samples}}},
        {"transactions", r.transactions},
        {"conflicts", conflicts},
    };
    return j.dump(2);
}

}  // namespace ballbar::workflow
