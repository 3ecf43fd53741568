// SPDX-License-Identifier: MIT
// `ballbar sync`: a station's database sent to a PostgreSQL server, where a plant keeps every station's
// sessions (docs/fleet.md). What it guarantees:
//
// - Idempotent: what the server has is not sent again; a second sync writes nothing.
// - Resumable: each session's records go in one transaction, its raw samples in chunks of one
//   transaction each (the session row locked, the chunk copied, the session's sample mark advanced). The
//   server is the only record of progress: a sync killed at any moment loses at most the transaction in
//   flight, and the next one continues from what the server has.
// - Safe with several stations (and two syncs of one station) at once: row locks, and the schema made
//   under an advisory lock.
// - It never deletes or replaces anything on the server. Records are inserted once; a session's own row
//   (its state, notes, instrument; the counts of what was sent) is updated by the station it came from.
//   An id that is on the server under another station is a conflict: reported, never merged.
// - The station's database is only read (one snapshot: a station may keep measuring meanwhile).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/fleet/pg.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::fleet {

/// The server schema this ballbar writes (table ballbar.schema_info). A server with a newer one is refused.
inline constexpr int kServerSchemaVersion = 1;

/// The version of ballbar's schema on the server (0: none). Throws Kind::newer_schema, naming both
/// versions and ending with `advice`, for one newer than this ballbar's.
int server_schema_version(pg::Connection& c, std::string_view advice);

/// Creates the server's schema `ballbar` where it is absent, migrates an older one, refuses a newer one
/// (Kind::newer_schema). Under an advisory lock: two stations starting at once do it once. Returns the
/// version found before (0: none).
int ensure_server_schema(pg::Connection& c);

struct SyncOptions {
    bool samples = false;                 ///< also the raw samples (COPY); results and models always
    std::int64_t chunk_samples = 200000;  ///< samples a transaction
    /// Called after each committed transaction with what was sent so far (progress on a terminal).
    std::function<void(std::string_view what)> progress;
};

/// An id on the server that belongs to another station.
struct SyncConflict {
    std::string kind;  ///< "session", "machine", "model", "result"
    std::string uuid;
    std::string other_station;
};

/// What one sync did. Row counts are rows written on the server (0 everywhere: nothing was new).
struct SyncReport {
    std::string station_uuid;
    std::string server;               ///< "database ballbar on db.plant:5432"
    int server_schema_before = 0;     ///< 0: this sync created it
    std::int64_t sessions_local = 0;  ///< sessions in the station's database
    std::int64_t sessions_sent = 0;   ///< sessions with anything new
    std::int64_t machines = 0, models = 0, sessions = 0, transitions = 0, points = 0, results = 0, segments = 0,
                 gaps = 0, samples = 0;
    std::int64_t transactions = 0;  ///< committed
    std::vector<SyncConflict> conflicts;
    std::int64_t rows() const {
        return machines + models + sessions + transitions + points + results + segments + gaps + samples;
    }
};

/// Sends the station's sessions, machines, models and results (and samples with options.samples) to
/// the server. Conflicts are reported in the result, the rest is sent. Throws FleetError for a server
/// that cannot be reached, refuses, or breaks the link (what was committed before stays), StorageError
/// for the station's database.
SyncReport sync(storage::Store& station, pg::Connection& server, const SyncOptions& options = {});

}  // namespace ballbar::fleet
