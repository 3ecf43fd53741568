// SPDX-License-Identifier: MIT
#include "ballbar/fleet/server_read.hpp"

#include "ballbar/fleet/sync.hpp"

namespace ballbar::fleet {
namespace {

void check_readable(pg::Connection& c) {
    if (server_schema_version(c, "update this ballbar to read it") == 0)
        throw FleetError(FleetError::Kind::server,
                         c.where() + " holds no ballbar data (no schema ballbar): sync a station to it first");
}

}  // namespace

std::vector<ServerSession> server_machine_sessions(pg::Connection& c, const std::string& machine,
                                                   const std::string& since) {
    check_readable(c);
    auto r = c.exec_params(
        "SELECT s.uuid::text, s.station_uuid::text, s.started_at, s.procedure, s.source, m.type, r.kind, "
        "r.payload_json FROM ballbar.sessions s JOIN ballbar.machines m ON m.uuid = s.machine_uuid "
        "LEFT JOIN ballbar.results r ON r.session_uuid = s.uuid "
        "WHERE s.state = 'completed' AND s.started_at >= $2 AND (m.asset_id = $1 OR (m.asset_id IS NULL AND "
        "m.type || CASE WHEN m.name = '' THEN '' ELSE ' ' || m.name END = $1)) "
        "ORDER BY s.started_at, s.uuid, r.created_at, r.uuid",
        {machine, since});
    std::vector<ServerSession> out;
    for (int i = 0; i < r.rows(); ++i) {
        if (out.empty() || out.back().uuid != r.text(i, 0))
            out.push_back({r.text(i, 0), r.text(i, 1), r.text(i, 2), r.text(i, 3), r.text(i, 4), r.text(i, 5), {}});
        if (!r.is_null(i, 6)) out.back().results.emplace_back(r.text(i, 6), r.text(i, 7));
    }
    return out;
}

std::string server_machine_file(pg::Connection& c, const std::string& asset_id) {
    auto r = c.exec_params(
        "SELECT machine_file_json FROM ballbar.machines WHERE asset_id = $1 AND machine_file_json <> '' "
        "ORDER BY coalesce(updated_at, registered_at) DESC NULLS LAST LIMIT 1",
        {asset_id});
    return r.rows() ? r.text(0, 0) : std::string();
}

}  // namespace ballbar::fleet
