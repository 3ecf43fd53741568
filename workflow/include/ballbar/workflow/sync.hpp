// SPDX-License-Identifier: MIT
// The sync use case: the station's database to a plant's PostgreSQL server (fleet/sync.hpp has the
// guarantees; docs/fleet.md the model and the server's set-up).
#pragma once

#include <string>

#include "ballbar/fleet/sync.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::workflow {

/// Connects to `conninfo` (a libpq connection string or URI, without a password) and syncs. Conflicts
/// are in the report; the front end decides what they mean for its exit.
fleet::SyncReport sync_station(storage::Store& station, const std::string& conninfo, const fleet::SyncOptions& options);

/// The report in the project's JSON vocabulary (docs/cli.md).
std::string sync_json(const fleet::SyncReport& report);

}  // namespace ballbar::workflow
