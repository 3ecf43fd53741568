// SPDX-License-Identifier: MIT
// Reading a machine's sessions back from the plant's server, for `ballbar trend --from CONNINFO`
// (docs/fleet.md): every station's completed sessions of one machine, with their results. Needs only
// SELECT on the schema (a reporting role).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "ballbar/fleet/pg.hpp"

namespace ballbar::fleet {

struct ServerSession {
    std::string uuid, station_uuid, started_at, procedure, source;
    std::string machine_type;                                  ///< "TTTRR", …
    std::vector<std::pair<std::string, std::string>> results;  ///< (kind, payload) by creation time
};

/// The completed sessions of `machine` — an asset id (on any station), or for machines registered
/// nowhere the label "TYPE name" — started on or after `since` (YYYY-MM-DD; "" = all), oldest first.
/// Throws FleetError when the server holds no ballbar schema or a newer one.
std::vector<ServerSession> server_machine_sessions(pg::Connection& c, const std::string& machine,
                                                   const std::string& since);

/// The machine file registered under `asset_id` (the latest edited of the stations'); "" when none.
std::string server_machine_file(pg::Connection& c, const std::string& asset_id);

}  // namespace ballbar::fleet
