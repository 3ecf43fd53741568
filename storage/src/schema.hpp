// SPDX-License-Identifier: MIT
// The schema migrations: kMigrations[i] takes a database from user_version i to i + 1.
#pragma once

#include <array>
#include <string_view>

namespace ballbar::storage::detail {

inline constexpr std::string_view kMigrationV1 = R"sql(
CREATE TABLE instruments (
  id INTEGER PRIMARY KEY,
  model TEXT NOT NULL DEFAULT '',
  serial TEXT NOT NULL DEFAULT '',
  firmware TEXT NOT NULL DEFAULT '',
  calibrated_length_mm REAL,
  calibration_date TEXT NOT NULL DEFAULT '',
  extra_json TEXT NOT NULL DEFAULT ''
);
CREATE TABLE machines (
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL DEFAULT '',
  type TEXT NOT NULL CHECK (type IN ('RRTTT', 'TTTRR', 'RTTTR')),
  geometry_json TEXT NOT NULL,
  UNIQUE (geometry_json)
);
CREATE TABLE sessions (
  id INTEGER PRIMARY KEY,
  uuid TEXT NOT NULL UNIQUE,
  machine_id INTEGER NOT NULL REFERENCES machines(id),
  instrument_id INTEGER REFERENCES instruments(id),
  source TEXT NOT NULL CHECK (source IN ('device', 'emulator', 'imported')),
  state TEXT NOT NULL CHECK (state IN ('created', 'running', 'completed', 'aborted', 'failed', 'interrupted')),
  operator TEXT NOT NULL DEFAULT '',
  procedure TEXT NOT NULL DEFAULT '',
  notes TEXT NOT NULL DEFAULT '',
  started_at TEXT NOT NULL,
  ended_at TEXT,
  metadata_json TEXT NOT NULL DEFAULT ''
);
CREATE INDEX sessions_by_state ON sessions(state);
CREATE TABLE session_transitions (
  id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(id),
  from_state TEXT,
  to_state TEXT NOT NULL,
  event TEXT NOT NULL,
  at TEXT NOT NULL
);
CREATE INDEX session_transitions_by_session ON session_transitions(session_id, id);
CREATE TABLE samples (
  session_id INTEGER NOT NULL,
  seq INTEGER NOT NULL,
  device_time_us INTEGER NOT NULL,
  displacement_nm INTEGER NOT NULL,
  flags INTEGER NOT NULL,
  bar_temp_mC INTEGER NOT NULL,
  PRIMARY KEY (session_id, seq)
) WITHOUT ROWID;
CREATE TABLE points (
  session_id INTEGER NOT NULL REFERENCES sessions(id),
  idx INTEGER NOT NULL,
  location INTEGER NOT NULL,
  point INTEGER NOT NULL,
  step INTEGER NOT NULL,
  X_mm REAL NOT NULL, Y_mm REAL NOT NULL, Z_mm REAL NOT NULL,
  A_rad REAL NOT NULL, B_rad REAL NOT NULL, C_rad REAL NOT NULL,
  socket_x_mm REAL NOT NULL, socket_y_mm REAL NOT NULL, socket_z_mm REAL NOT NULL,
  nominal_mm REAL NOT NULL,
  mean_mm REAL NOT NULL,
  std_mm REAL,
  n INTEGER NOT NULL,
  first_seq INTEGER,
  last_seq INTEGER,
  time_s REAL NOT NULL,
  bar_temp_C REAL, air_temp_C REAL, machine_temp_C REAL,
  PRIMARY KEY (session_id, idx)
) WITHOUT ROWID;
CREATE TABLE models (
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL,
  version INTEGER NOT NULL,
  parent_id INTEGER REFERENCES models(id),
  params_json TEXT NOT NULL,
  notes TEXT NOT NULL DEFAULT '',
  created_at TEXT NOT NULL,
  UNIQUE (name, version)
);
CREATE TABLE model_sessions (
  model_id INTEGER NOT NULL REFERENCES models(id),
  session_id INTEGER NOT NULL REFERENCES sessions(id),
  PRIMARY KEY (model_id, session_id)
) WITHOUT ROWID;
CREATE TABLE results (
  id INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(id),
  kind TEXT NOT NULL,
  payload_json TEXT NOT NULL,
  model_id INTEGER REFERENCES models(id),
  producer TEXT NOT NULL DEFAULT '',
  created_at TEXT NOT NULL
);
CREATE INDEX results_by_session ON results(session_id, kind);
)sql";

// v2: the guided procedure's own steps (acquisition's state machine) join the session's lifecycle in
// session_transitions, told apart by `scope`; v1 kept them as results of kind
// 'acquisition.transition', which move here (in their order, with their time).
inline constexpr std::string_view kMigrationV2 = R"sql(
ALTER TABLE session_transitions ADD COLUMN scope TEXT NOT NULL DEFAULT 'session'
  CHECK (scope IN ('session', 'procedure'));
ALTER TABLE session_transitions ADD COLUMN detail TEXT NOT NULL DEFAULT '';
CREATE INDEX session_transitions_by_scope ON session_transitions(session_id, scope, id);
INSERT INTO session_transitions(session_id, from_state, to_state, event, at, scope, detail)
  SELECT session_id, json_extract(payload_json, '$.from'), coalesce(json_extract(payload_json, '$.to'), ''),
         coalesce(json_extract(payload_json, '$.event'), ''), created_at, 'procedure',
         coalesce(json_extract(payload_json, '$.detail'), '')
  FROM results WHERE kind = 'acquisition.transition' AND json_valid(payload_json) ORDER BY id;
DELETE FROM results WHERE kind = 'acquisition.transition' AND json_valid(payload_json);
)sql";

// v3: a session's samples in runs on one device clock (a connection; a resume), so readers can build
// one monotonic session time across reconnects and resumes (SessionClock).
inline constexpr std::string_view kMigrationV3 = R"sql(
CREATE TABLE sample_segments (
  session_id INTEGER NOT NULL REFERENCES sessions(id),
  first_seq INTEGER NOT NULL,
  device_time_us INTEGER NOT NULL,
  started_at TEXT NOT NULL,
  PRIMARY KEY (session_id, first_seq)
) WITHOUT ROWID;
)sql";

// v4: the instrument's resolution and actually measured reading rate with every sample, through its
// segment (a sample belongs to the segment with the largest first_seq ≤ its seq; the view
// sample_instruments gives them per sample). NULL: not known (the project's own instrument, imports).
// Sessions of v3 whose gauge wrote them once as the session's `instrument` result get them on each of
// their segments (the values that result measured).
inline constexpr std::string_view kMigrationV4 = R"sql(
ALTER TABLE sample_segments ADD COLUMN resolution_mm REAL CHECK (resolution_mm IS NULL OR resolution_mm > 0);
ALTER TABLE sample_segments ADD COLUMN reading_rate_hz REAL CHECK (reading_rate_hz IS NULL OR reading_rate_hz > 0);
UPDATE sample_segments SET
  resolution_mm = (SELECT json_extract(r.payload_json, '$.resolution_mm') FROM results r
                   WHERE r.session_id = sample_segments.session_id AND r.kind = 'instrument' AND json_valid(r.payload_json)
                     AND json_extract(r.payload_json, '$.resolution_mm') > 0 ORDER BY r.id DESC LIMIT 1),
  reading_rate_hz = (SELECT json_extract(r.payload_json, '$.reading_rate_hz') FROM results r
                     WHERE r.session_id = sample_segments.session_id AND r.kind = 'instrument' AND json_valid(r.payload_json)
                       AND json_extract(r.payload_json, '$.reading_rate_hz') > 0 ORDER BY r.id DESC LIMIT 1);
CREATE VIEW sample_instruments AS
  SELECT s.session_id, s.seq, g.first_seq AS segment_first_seq, g.resolution_mm, g.reading_rate_hz
  FROM samples s JOIN sample_segments g ON g.session_id = s.session_id AND g.first_seq =
    (SELECT max(h.first_seq) FROM sample_segments h WHERE h.session_id = s.session_id AND h.first_seq <= s.seq);
)sql";

// v5: the file an imported session came from: the SHA-256 of its bytes, its name and size, so that the
// same content imported again is recognised (imports.hpp). Sessions imported before have no row.
inline constexpr std::string_view kMigrationV5 = R"sql(
CREATE TABLE imports (
  session_id INTEGER PRIMARY KEY REFERENCES sessions(id),
  content_sha256 TEXT NOT NULL CHECK (length(content_sha256) = 64),
  file_name TEXT NOT NULL DEFAULT '',
  bytes INTEGER NOT NULL CHECK (bytes >= 0),
  imported_at TEXT NOT NULL
);
CREATE INDEX imports_by_content ON imports(content_sha256);
)sql";

// v6: the gaps in a session's stream (frames the instrument sent and the host lost): where (the stored
// seq of the first sample after the gap, which also carries the flag kSampleAfterGap), how long (the
// instrument's time between the samples either side) and why. Sessions stored before v6 have none
// recorded (their gaps were not kept).
inline constexpr std::string_view kMigrationV6 = R"sql(
CREATE TABLE sample_gaps (
  session_id INTEGER NOT NULL REFERENCES sessions(id),
  before_seq INTEGER NOT NULL,
  duration_s REAL,
  cause TEXT NOT NULL,
  PRIMARY KEY (session_id, before_seq)
) WITHOUT ROWID;
)sql";

// v7: identities that survive a fleet (docs/fleet.md). The station: this database's own uuid. The
// machine registry: a machine an operator registered has an asset id (the shop's name for it, unique),
// a location and its whole machine file (travel, dialect, feed, tolerances); a machine known only by the
// geometry a session was measured with has none (asset_id NULL; one row per geometry, as before). Two
// registered machines may share a geometry (two mills of one model): the table is rebuilt without v1's
// UNIQUE (geometry_json), which the index below keeps for unregistered ones. Machines, models and
// results get a uuid (122 random bits: ballbar_uuid(), the Store's, per row); sessions keep theirs.
// Store::migrate runs this with foreign keys off and checks them before it commits.
inline constexpr std::string_view kMigrationV7 = R"sql(
CREATE TABLE station (
  id INTEGER PRIMARY KEY CHECK (id = 1),
  uuid TEXT NOT NULL,
  created_at TEXT NOT NULL
);
INSERT INTO station(id, uuid, created_at) VALUES (1, ballbar_uuid(), strftime('%Y-%m-%dT%H:%M:%fZ', 'now'));
CREATE TABLE machines_v7 (
  id INTEGER PRIMARY KEY,
  uuid TEXT NOT NULL UNIQUE,
  asset_id TEXT UNIQUE CHECK (asset_id IS NULL OR length(asset_id) > 0),
  name TEXT NOT NULL DEFAULT '',
  type TEXT NOT NULL CHECK (type IN ('RRTTT', 'TTTRR', 'RTTTR')),
  geometry_json TEXT NOT NULL,
  location TEXT NOT NULL DEFAULT '',
  machine_file_json TEXT NOT NULL DEFAULT '',
  registered_at TEXT,
  updated_at TEXT
);
INSERT INTO machines_v7(id, uuid, name, type, geometry_json)
  SELECT id, ballbar_uuid(), name, type, geometry_json FROM machines ORDER BY id;
DROP TABLE machines;
ALTER TABLE machines_v7 RENAME TO machines;
CREATE UNIQUE INDEX machines_unregistered_by_geometry ON machines(geometry_json) WHERE asset_id IS NULL;
ALTER TABLE models ADD COLUMN uuid TEXT;
UPDATE models SET uuid = ballbar_uuid();
CREATE UNIQUE INDEX models_by_uuid ON models(uuid);
ALTER TABLE results ADD COLUMN uuid TEXT;
UPDATE results SET uuid = ballbar_uuid();
CREATE UNIQUE INDEX results_by_uuid ON results(uuid);
)sql";

inline constexpr std::array<std::string_view, 7> kMigrations = {kMigrationV1, kMigrationV2, kMigrationV3, kMigrationV4,
                                                                kMigrationV5, kMigrationV6, kMigrationV7};

}  // namespace ballbar::storage::detail
