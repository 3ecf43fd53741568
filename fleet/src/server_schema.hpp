// SPDX-License-Identifier: MIT
// The server's schema `ballbar`, version by version (docs/fleet.md). A version's text never changes once
// released: a later version is a migration appended to kServerMigrations.
//
// What a station sends keeps its station's words: times as the ISO 8601 text the station wrote, JSON
// documents as the text it stored (byte for byte, so counts and checksums compare with the station's;
// cast to timestamptz and jsonb in queries). Every table is keyed by uuids, never by a station's row ids.
// ballbar.samples alone has no foreign key to its session: PostgreSQL checks one by a trigger per row,
// which made COPY 3.5 times slower (181,279 rows: 1.0–1.35 s against 0.28–0.40 s with the primary key
// alone); the sync writes a chunk in a transaction that holds its session's row locked, so no sample
// is written without its session.
#pragma once

#include <array>
#include <string_view>

namespace ballbar::fleet::detail {

inline constexpr std::string_view kServerSchemaV1 = R"sql(
CREATE TABLE ballbar.schema_info (
  id integer PRIMARY KEY CHECK (id = 1),
  version integer NOT NULL,
  migrated_at timestamptz NOT NULL DEFAULT now()
);
CREATE TABLE ballbar.stations (
  uuid uuid PRIMARY KEY,
  host text NOT NULL DEFAULT '',
  software text NOT NULL DEFAULT '',
  first_sync_at timestamptz NOT NULL DEFAULT now(),
  last_sync_at timestamptz NOT NULL DEFAULT now()
);
CREATE TABLE ballbar.machines (
  uuid uuid PRIMARY KEY,
  station_uuid uuid NOT NULL REFERENCES ballbar.stations(uuid),
  asset_id text,
  name text NOT NULL,
  type text NOT NULL,
  geometry_json text NOT NULL,
  location text NOT NULL,
  machine_file_json text NOT NULL,
  registered_at text,
  updated_at text
);
CREATE INDEX machines_by_asset ON ballbar.machines(asset_id);
CREATE TABLE ballbar.models (
  uuid uuid PRIMARY KEY,
  station_uuid uuid NOT NULL REFERENCES ballbar.stations(uuid),
  name text NOT NULL,
  version integer NOT NULL,
  parent_uuid uuid REFERENCES ballbar.models(uuid),
  params_json text NOT NULL,
  notes text NOT NULL,
  created_at text NOT NULL
);
CREATE TABLE ballbar.sessions (
  uuid uuid PRIMARY KEY,
  station_uuid uuid NOT NULL REFERENCES ballbar.stations(uuid),
  machine_uuid uuid NOT NULL REFERENCES ballbar.machines(uuid),
  instrument_model text,
  instrument_serial text,
  instrument_firmware text,
  instrument_calibrated_length_mm double precision,
  instrument_calibration_date text,
  instrument_extra_json text,
  source text NOT NULL,
  state text NOT NULL,
  operator text NOT NULL,
  procedure text NOT NULL,
  notes text NOT NULL,
  started_at text NOT NULL,
  ended_at text,
  metadata_json text NOT NULL,
  samples_at_station bigint NOT NULL DEFAULT 0,
  samples_next_seq bigint NOT NULL DEFAULT 0,
  sync_digest text NOT NULL DEFAULT '',
  synced_at timestamptz NOT NULL DEFAULT now()
);
CREATE INDEX sessions_by_machine ON ballbar.sessions(machine_uuid, started_at);
CREATE INDEX sessions_by_station ON ballbar.sessions(station_uuid);
CREATE TABLE ballbar.session_transitions (
  session_uuid uuid NOT NULL REFERENCES ballbar.sessions(uuid),
  ord integer NOT NULL,
  scope text NOT NULL,
  from_state text,
  to_state text NOT NULL,
  event text NOT NULL,
  detail text NOT NULL,
  at text NOT NULL,
  PRIMARY KEY (session_uuid, ord)
);
CREATE TABLE ballbar.points (
  session_uuid uuid NOT NULL REFERENCES ballbar.sessions(uuid),
  idx integer NOT NULL,
  location integer NOT NULL, point integer NOT NULL, step integer NOT NULL,
  x_mm double precision NOT NULL, y_mm double precision NOT NULL, z_mm double precision NOT NULL,
  a_rad double precision NOT NULL, b_rad double precision NOT NULL, c_rad double precision NOT NULL,
  socket_x_mm double precision NOT NULL, socket_y_mm double precision NOT NULL, socket_z_mm double precision NOT NULL,
  nominal_mm double precision NOT NULL,
  mean_mm double precision NOT NULL,
  std_mm double precision,
  n integer NOT NULL,
  first_seq bigint, last_seq bigint,
  time_s double precision NOT NULL,
  bar_temp_c double precision, air_temp_c double precision, machine_temp_c double precision,
  PRIMARY KEY (session_uuid, idx)
);
CREATE TABLE ballbar.results (
  uuid uuid PRIMARY KEY,
  session_uuid uuid NOT NULL REFERENCES ballbar.sessions(uuid),
  kind text NOT NULL,
  payload_json text NOT NULL,
  model_uuid uuid REFERENCES ballbar.models(uuid),
  producer text NOT NULL,
  created_at text NOT NULL
);
CREATE INDEX results_by_session ON ballbar.results(session_uuid, kind);
CREATE TABLE ballbar.model_sessions (
  model_uuid uuid NOT NULL REFERENCES ballbar.models(uuid),
  session_uuid uuid NOT NULL REFERENCES ballbar.sessions(uuid),
  PRIMARY KEY (model_uuid, session_uuid)
);
CREATE TABLE ballbar.sample_segments (
  session_uuid uuid NOT NULL REFERENCES ballbar.sessions(uuid),
  first_seq bigint NOT NULL,
  device_time_us bigint NOT NULL,
  started_at text NOT NULL,
  resolution_mm double precision,
  reading_rate_hz double precision,
  PRIMARY KEY (session_uuid, first_seq)
);
CREATE TABLE ballbar.sample_gaps (
  session_uuid uuid NOT NULL REFERENCES ballbar.sessions(uuid),
  before_seq bigint NOT NULL,
  duration_s double precision,
  cause text NOT NULL,
  PRIMARY KEY (session_uuid, before_seq)
);
CREATE TABLE ballbar.samples (
  session_uuid uuid NOT NULL,
  seq bigint NOT NULL,
  device_time_us bigint NOT NULL,
  displacement_nm bigint NOT NULL,
  flags integer NOT NULL,
  bar_temp_mc integer NOT NULL,
  PRIMARY KEY (session_uuid, seq)
);
INSERT INTO ballbar.schema_info(id, version) VALUES (1, 1);
)sql";

inline constexpr std::array<std::string_view, 1> kServerMigrations = {kServerSchemaV1};

}  // namespace ballbar::fleet::detail
