// SPDX-License-Identifier: MIT
#include "ballbar/fleet/sync.hpp"

#include <unistd.h>

#include <charconv>
#include <limits>
#include <map>
#include <set>

#include "ballbar/storage/imports.hpp"
#include "server_schema.hpp"

namespace ballbar::fleet {
namespace {

using pg::Param;
using Row = std::vector<Param>;

// A key no other application is likely to take for its advisory lock: "BBARSCHM".
constexpr std::int64_t kSchemaLockKey = 0x4242415253434834;

// Local rows as text -------------------------------------------------------------------------------

std::string double_text(double v) {
    char b[32];
    const auto [end, ec] = std::to_chars(b, b + sizeof b, v);  // shortest text that reads back exactly
    return std::string(b, ec == std::errc() ? end : b);
}

/// Column `i` of a station row as a parameter: `t` text, `i` integer, `d` double (exactly).
Param column(storage::Statement& st, int i, char type) {
    if (st.is_null(i)) return std::nullopt;
    switch (type) {
        case 'i':
            return std::to_string(st.column_int(i));
        case 'd':
            return double_text(st.column_double(i));
        default:
            return st.column_text(i);
    }
}

/// Every row of a station query; `types` has one letter a column.
std::vector<Row> rows_of(storage::Statement& st, std::string_view types) {
    std::vector<Row> rows;
    while (st.step()) {
        Row r;
        r.reserve(types.size());
        for (std::size_t i = 0; i < types.size(); ++i) r.push_back(column(st, static_cast<int>(i), types[i]));
        rows.push_back(std::move(r));
    }
    return rows;
}

/// Adds rows to the digest text: fields separated by \x1f, rows by \x1e, NULL as \x1d.
void digest_rows(std::string& text, std::string_view table, const std::vector<Row>& rows) {
    text += table;
    for (const Row& r : rows) {
        for (const Param& p : r) {
            text += p ? *p : std::string("\x1d");
            text += '\x1f';
        }
        text += '\x1e';
    }
}

/// `{a,b,c}`: a text array of uuids for `= ANY($1::uuid[])`.
std::string uuid_array(const std::vector<std::string>& uuids) {
    std::string s = "{";
    for (std::size_t i = 0; i < uuids.size(); ++i) s += (i ? "," : "") + uuids[i];
    return s + "}";
}

/// INSERT … VALUES (…), (…) ON CONFLICT DO NOTHING in statements of at most 1000 rows; returns the rows
/// the server inserted (the ones it did not have).
std::int64_t insert_rows(pg::Connection& c, std::string_view table, std::string_view columns, std::size_t width,
                         const std::vector<Row>& rows) {
    std::int64_t inserted = 0;
    constexpr std::size_t kRowsAStatement = 1000;
    for (std::size_t at = 0; at < rows.size(); at += kRowsAStatement) {
        const std::size_t n = std::min(kRowsAStatement, rows.size() - at);
        std::string sql = "INSERT INTO ballbar." + std::string(table) + " (" + std::string(columns) + ") VALUES ";
        std::vector<Param> params;
        params.reserve(n * width);
        for (std::size_t r = 0; r < n; ++r) {
            sql += r ? ",(" : "(";
            for (std::size_t k = 0; k < width; ++k) {
                params.push_back(rows[at + r][k]);
                sql += (k ? ",$" : "$") + std::to_string(params.size());
            }
            sql += ')';
        }
        sql += " ON CONFLICT DO NOTHING";
        inserted += c.exec_params(sql, params).affected();
    }
    return inserted;
}

// The station's records ----------------------------------------------------------------------------

constexpr std::string_view kMachineColumns =
    "uuid, station_uuid, asset_id, name, type, geometry_json, location, machine_file_json, registered_at, updated_at";
constexpr std::string_view kModelColumns =
    "uuid, station_uuid, name, version, parent_uuid, params_json, notes, created_at";
constexpr std::string_view kSessionColumns =
    "uuid, station_uuid, machine_uuid, instrument_model, instrument_serial, instrument_firmware, "
    "instrument_calibrated_length_mm, instrument_calibration_date, instrument_extra_json, source, state, operator, "
    "procedure, notes, started_at, ended_at, metadata_json, samples_at_station, sync_digest";
constexpr std::size_t kSessionWidth = 19;
constexpr std::string_view kTransitionColumns = "session_uuid, ord, scope, from_state, to_state, event, detail, at";
constexpr std::string_view kPointColumns =
    "session_uuid, idx, location, point, step, x_mm, y_mm, z_mm, a_rad, b_rad, c_rad, socket_x_mm, socket_y_mm, "
    "socket_z_mm, nominal_mm, mean_mm, std_mm, n, first_seq, last_seq, time_s, bar_temp_c, air_temp_c, machine_temp_c";
constexpr std::string_view kResultColumns = "uuid, session_uuid, kind, payload_json, model_uuid, producer, created_at";
constexpr std::string_view kSegmentColumns =
    "session_uuid, first_seq, device_time_us, started_at, resolution_mm, reading_rate_hz";
constexpr std::string_view kGapColumns = "session_uuid, before_seq, duration_s, cause";

/// One session of the station, everything but its samples, and its digest.
struct LocalSession {
    std::int64_t id = 0;
    std::string uuid;
    Row row;  ///< kSessionColumns
    std::vector<Row> transitions, points, results, model_links, segments, gaps;
    std::int64_t samples = 0;
    std::int64_t next_seq = 0;  ///< one past the last sample's seq
    std::string digest;
};

LocalSession read_session(storage::Database& db, std::int64_t id, const std::string& station) {
    LocalSession s;
    s.id = id;
    {
        auto st = db.prepare(
            "SELECT s.uuid, m.uuid, i.model, i.serial, i.firmware, i.calibrated_length_mm, i.calibration_date, "
            "i.extra_json, s.source, s.state, s.operator, s.procedure, s.notes, s.started_at, s.ended_at, "
            "s.metadata_json FROM sessions s JOIN machines m ON m.id = s.machine_id "
            "LEFT JOIN instruments i ON i.id = s.instrument_id WHERE s.id = ?");
        st.bind(1, id);
        auto rows = rows_of(st, "tttttdtttttttttt");
        s.row = std::move(rows.at(0));
        s.uuid = *s.row[0];
        s.row.insert(s.row.begin() + 1, station);
    }
    auto per_session = [&](const char* sql, std::string_view types) {
        auto st = db.prepare(sql);
        st.bind(1, id);
        auto rows = rows_of(st, types);
        for (Row& r : rows) r.insert(r.begin(), s.uuid);
        return rows;
    };
    s.transitions = per_session(
        "SELECT scope, from_state, to_state, event, detail, at FROM session_transitions WHERE session_id = ? "
        "ORDER BY id",
        "tttttt");
    for (std::size_t i = 0; i < s.transitions.size(); ++i)
        s.transitions[i].insert(s.transitions[i].begin() + 1, std::to_string(i));
    s.points = per_session(
        "SELECT idx, location, point, step, X_mm, Y_mm, Z_mm, A_rad, B_rad, C_rad, socket_x_mm, socket_y_mm, "
        "socket_z_mm, nominal_mm, mean_mm, std_mm, n, first_seq, last_seq, time_s, bar_temp_C, air_temp_C, "
        "machine_temp_C FROM points WHERE session_id = ? ORDER BY idx",
        "iiiiddddddddddddiiidddd");
    s.results = per_session(
        "SELECT r.uuid, r.kind, r.payload_json, m.uuid, r.producer, r.created_at FROM results r "
        "LEFT JOIN models m ON m.id = r.model_id WHERE r.session_id = ? ORDER BY r.id",
        "tttttt");
    for (Row& r : s.results) std::swap(r[0], r[1]);  // uuid first, then the session's
    s.model_links = per_session(
        "SELECT m.uuid FROM model_sessions ms JOIN models m ON m.id = ms.model_id WHERE ms.session_id = ? "
        "ORDER BY m.id",
        "t");
    for (Row& r : s.model_links) std::swap(r[0], r[1]);  // model, session
    s.segments = per_session(
        "SELECT first_seq, device_time_us, started_at, resolution_mm, reading_rate_hz FROM sample_segments "
        "WHERE session_id = ? ORDER BY first_seq",
        "iitdd");
    s.gaps = per_session(
        "SELECT before_seq, duration_s, cause FROM sample_gaps WHERE session_id = ? ORDER BY before_seq", "idt");
    {
        auto st = db.prepare("SELECT count(*), coalesce(max(seq) + 1, 0) FROM samples WHERE session_id = ?");
        st.bind(1, id);
        st.step();
        s.samples = st.column_int(0);
        s.next_seq = st.column_int(1);
    }
    s.row.push_back(std::to_string(s.samples));
    std::string text;
    digest_rows(text, "session", {s.row});
    digest_rows(text, "transitions", s.transitions);
    digest_rows(text, "points", s.points);
    digest_rows(text, "results", s.results);
    digest_rows(text, "models", s.model_links);
    digest_rows(text, "segments", s.segments);
    digest_rows(text, "gaps", s.gaps);
    s.digest = storage::sha256_hex(text);
    s.row.push_back(s.digest);
    return s;
}

/// The server's mark of one session: whose it is, what was sent last, how far its samples go.
struct ServerMark {
    std::string station;
    std::string digest;
    std::int64_t next_seq = 0;
};

class Syncer {
  public:
    Syncer(storage::Store& store, pg::Connection& c, const SyncOptions& o) : store_(store), c_(c), o_(o) {}

    SyncReport run() {
        r_.server = c_.where();
        r_.server_schema_before = ensure_server_schema(c_);
        r_.station_uuid = store_.station_uuid();
        storage::Transaction snapshot(store_.db(), /*immediate=*/false);  // one consistent view, read only
        send_station_machines_models();
        std::vector<std::int64_t> ids;
        std::vector<std::string> uuids;
        {
            auto st = store_.db().prepare("SELECT id, uuid FROM sessions ORDER BY id");
            while (st.step()) {
                ids.push_back(st.column_int(0));
                uuids.push_back(st.column_text(1));
            }
        }
        r_.sessions_local = static_cast<std::int64_t>(ids.size());
        const auto marks = server_marks(uuids);
        for (std::int64_t id : ids) {
            LocalSession s = read_session(store_.db(), id, r_.station_uuid);
            const auto m = marks.find(s.uuid);
            if (m != marks.end() && m->second.station != r_.station_uuid) {
                r_.conflicts.push_back({"session", s.uuid, m->second.station});
                continue;
            }
            const bool records_there = m != marks.end() && m->second.digest == s.digest;
            const bool samples_there = !o_.samples || (m != marks.end() && m->second.next_seq >= s.next_seq);
            if (records_there && samples_there) continue;
            ++r_.sessions_sent;
            if (!records_there && !send_session(s)) continue;
            if (!samples_there) send_samples(s);
        }
        snapshot.commit();
        if (r_.rows() > 0)
            c_.exec_params("UPDATE ballbar.stations SET last_sync_at = now() WHERE uuid = $1", {r_.station_uuid});
        return r_;
    }

  private:
    void committed(pg::Transaction& t, std::string_view what) {
        t.commit();
        ++r_.transactions;
        if (o_.progress) o_.progress(what);
    }

    /// The station row, its machines and models (before any session refers to them).
    void send_station_machines_models() {
        char host[256] = {};
        if (gethostname(host, sizeof host - 1) != 0) host[0] = 0;
        std::vector<Row> machines, models;
        {
            auto st = store_.db().prepare(
                "SELECT uuid, asset_id, name, type, geometry_json, location, machine_file_json, registered_at, "
                "updated_at FROM machines ORDER BY id");
            machines = rows_of(st, "ttttttttt");
            for (Row& r : machines) r.insert(r.begin() + 1, r_.station_uuid);
        }
        {
            auto st = store_.db().prepare(
                "SELECT m.uuid, m.name, m.version, p.uuid, m.params_json, m.notes, m.created_at FROM models m "
                "LEFT JOIN models p ON p.id = m.parent_id ORDER BY m.id");
            models = rows_of(st, "ttitttt");
            for (Row& r : models) r.insert(r.begin() + 1, r_.station_uuid);
        }
        pg::Transaction t(c_);
        c_.exec_params("INSERT INTO ballbar.stations(uuid, host, software) VALUES ($1, $2, $3) ON CONFLICT DO NOTHING",
                       {r_.station_uuid, std::string(host), "ballbar " BALLBAR_VERSION});
        // Machines: new ones inserted; a registered machine's edits (name, location, machine file) update
        // the row of the station it belongs to; another station's uuid is a conflict.
        std::vector<std::string> uuids;
        for (const Row& r : machines) uuids.push_back(*r[0]);
        auto there =
            c_.exec_params("SELECT uuid::text, station_uuid::text, " + std::string(kMachineColumns.substr(20)) +
                               " FROM ballbar.machines WHERE uuid = ANY($1::uuid[])",
                           {uuid_array(uuids)});
        std::map<std::string, Row> server;
        for (int i = 0; i < there.rows(); ++i) {
            Row row;
            for (int k = 0; k < 10; ++k) row.push_back(there.opt_text(i, k));
            server[*row[0]] = std::move(row);
        }
        std::vector<Row> fresh;
        for (const Row& r : machines) {
            const auto s = server.find(*r[0]);
            if (s == server.end()) {
                fresh.push_back(r);
            } else if (*s->second[1] != r_.station_uuid) {
                r_.conflicts.push_back({"machine", *r[0], *s->second[1]});
                refused_machines_.insert(*r[0]);
            } else if (s->second != r) {
                r_.machines += c_.exec_params(
                                     "UPDATE ballbar.machines SET asset_id = $3, name = $4, type = $5, "
                                     "geometry_json = $6, location = $7, machine_file_json = $8, registered_at = $9, "
                                     "updated_at = $10 WHERE uuid = $1 AND station_uuid = $2",
                                     r)
                                   .affected();
            }
        }
        r_.machines += insert_rows(c_, "machines", kMachineColumns, 10, fresh);
        // Models: immutable once saved; inserted in the station's order, parents first.
        uuids.clear();
        for (const Row& r : models) uuids.push_back(*r[0]);
        auto owners =
            c_.exec_params("SELECT uuid::text, station_uuid::text FROM ballbar.models WHERE uuid = ANY($1::uuid[])",
                           {uuid_array(uuids)});
        std::map<std::string, std::string> owner;
        for (int i = 0; i < owners.rows(); ++i) owner[owners.text(i, 0)] = owners.text(i, 1);
        std::vector<Row> new_models;
        for (const Row& r : models) {
            const auto o = owner.find(*r[0]);
            if (o == owner.end()) {
                new_models.push_back(r);
            } else if (o->second != r_.station_uuid) {
                r_.conflicts.push_back({"model", *r[0], o->second});
            }
        }
        r_.models += insert_rows(c_, "models", kModelColumns, 8, new_models);
        committed(t, "machines and models");
    }

    std::map<std::string, ServerMark> server_marks(const std::vector<std::string>& uuids) {
        std::map<std::string, ServerMark> marks;
        auto r = c_.exec_params(
            "SELECT uuid::text, station_uuid::text, sync_digest, samples_next_seq FROM ballbar.sessions "
            "WHERE uuid = ANY($1::uuid[])",
            {uuid_array(uuids)});
        for (int i = 0; i < r.rows(); ++i) marks[r.text(i, 0)] = {r.text(i, 1), r.text(i, 2), r.integer(i, 3)};
        return marks;
    }

    /// The session row locked; empty when it belongs to another station (reported).
    bool lock_own_session(const LocalSession& s, std::string* digest = nullptr, std::int64_t* next_seq = nullptr) {
        auto r = c_.exec_params(
            "SELECT station_uuid::text, sync_digest, samples_next_seq FROM ballbar.sessions WHERE uuid = $1 FOR UPDATE",
            {s.uuid});
        if (r.text(0, 0) != r_.station_uuid) {
            r_.conflicts.push_back({"session", s.uuid, r.text(0, 0)});
            return false;
        }
        if (digest) *digest = r.text(0, 1);
        if (next_seq) *next_seq = r.integer(0, 2);
        return true;
    }

    /// The session's records in one transaction. False: not the station's (a conflict).
    bool send_session(const LocalSession& s) {
        if (refused_machines_.count(*s.row[2])) {
            r_.conflicts.push_back({"session", s.uuid, "(its machine " + *s.row[2] + " is another station's)"});
            return false;
        }
        pg::Transaction t(c_);
        Row fresh = s.row;
        fresh[18] = std::string();  // the digest is set by the update below, with what was sent
        const std::int64_t inserted = insert_rows(c_, "sessions", kSessionColumns, kSessionWidth, {fresh});
        std::string digest;
        if (!lock_own_session(s, &digest)) return false;
        if (digest == s.digest) return true;  // another sync of this station sent it meanwhile
        // What may change on the station after a sync: the lifecycle, the notes, the instrument.
        const Row& v = s.row;
        const std::int64_t updated =
            c_.exec_params(
                  "UPDATE ballbar.sessions SET instrument_model = $3, instrument_serial = $4, instrument_firmware = "
                  "$5, "
                  "instrument_calibrated_length_mm = $6, instrument_calibration_date = $7, instrument_extra_json = $8, "
                  "state = $9, notes = $10, ended_at = $11, metadata_json = $12, samples_at_station = $13, "
                  "sync_digest = $14, synced_at = now() WHERE uuid = $1 AND station_uuid = $2",
                  {v[0], v[1], v[3], v[4], v[5], v[6], v[7], v[8], v[10], v[13], v[15], v[16], v[17], v[18]})
                .affected();
        if (inserted > 0 || updated > 0) ++r_.sessions;
        r_.transitions += insert_rows(c_, "session_transitions", kTransitionColumns, 8, s.transitions);
        r_.points += insert_rows(c_, "points", kPointColumns, 24, s.points);
        const std::int64_t results = insert_rows(c_, "results", kResultColumns, 7, s.results);
        if (results < static_cast<std::int64_t>(s.results.size())) result_conflicts(s);
        r_.results += results;
        insert_rows(c_, "model_sessions", "model_uuid, session_uuid", 2, s.model_links);
        r_.segments += insert_rows(c_, "sample_segments", kSegmentColumns, 6, s.segments);
        for (const Row& g : s.segments)  // the instrument's figures are set on a segment after it began
            c_.exec_params(
                "UPDATE ballbar.sample_segments SET resolution_mm = $3, reading_rate_hz = $4 WHERE session_uuid = $1 "
                "AND first_seq = $2 AND (resolution_mm, reading_rate_hz) IS DISTINCT FROM ($3::float8, $4::float8)",
                {g[0], g[1], g[4], g[5]});
        r_.gaps += insert_rows(c_, "sample_gaps", kGapColumns, 4, s.gaps);
        committed(t, "session " + s.uuid);
        return true;
    }

    /// Results of this session the server holds under another session (of another station).
    void result_conflicts(const LocalSession& s) {
        std::vector<std::string> uuids;
        for (const Row& r : s.results) uuids.push_back(*r[0]);
        auto r = c_.exec_params(
            "SELECT r.uuid::text, x.station_uuid::text FROM ballbar.results r JOIN ballbar.sessions x ON "
            "x.uuid = r.session_uuid WHERE r.uuid = ANY($1::uuid[]) AND r.session_uuid <> $2",
            {uuid_array(uuids), s.uuid});
        for (int i = 0; i < r.rows(); ++i) r_.conflicts.push_back({"result", r.text(i, 0), r.text(i, 1)});
    }

    /// The session's raw samples by COPY, a chunk a transaction, from where the server's mark is.
    void send_samples(const LocalSession& s) {
        auto st = store_.db().prepare(
            "SELECT seq, device_time_us, displacement_nm, flags, bar_temp_mC FROM samples WHERE session_id = ? "
            "AND seq >= ? AND seq < ? ORDER BY seq LIMIT ?");
        std::string data;
        for (;;) {
            pg::Transaction t(c_);
            std::int64_t next = 0;
            if (!lock_own_session(s, nullptr, &next)) return;
            if (next >= s.next_seq) return;
            st.reset();
            st.bind(1, s.id).bind(2, next).bind(3, s.next_seq).bind(4, o_.chunk_samples);
            // Streamed in pieces of 64 KiB: the server parses one while the next is read and formatted.
            c_.begin_copy(
                "COPY ballbar.samples (session_uuid, seq, device_time_us, displacement_nm, flags, bar_temp_mc) FROM "
                "STDIN");
            data.clear();
            std::int64_t last = next - 1;
            char b[24];
            auto field = [&](std::int64_t v, char end) {
                const auto [p, ec] = std::to_chars(b, b + sizeof b, v);
                data.append(b, p);
                data += end;
            };
            while (st.step()) {
                data += s.uuid;
                data += '\t';
                last = st.column_int(0);
                field(last, '\t');
                field(st.column_int(1), '\t');
                field(st.column_int(2), '\t');
                field(st.column_int(3), '\t');
                field(st.column_int(4), '\n');
                if (data.size() >= (64u << 10)) {
                    c_.put_copy(data);
                    data.clear();
                }
            }
            c_.put_copy(data);
            const std::int64_t copied = c_.end_copy();
            if (copied == 0) return;
            r_.samples += copied;
            c_.exec_params("UPDATE ballbar.sessions SET samples_next_seq = $2 WHERE uuid = $1",
                           {s.uuid, std::to_string(last + 1)});
            committed(t, "samples of session " + s.uuid);
        }
    }

    storage::Store& store_;
    pg::Connection& c_;
    const SyncOptions& o_;
    SyncReport r_;
    std::set<std::string> refused_machines_;
};

}  // namespace

int server_schema_version(pg::Connection& c, std::string_view advice) {
    if (c.exec("SELECT to_regclass('ballbar.schema_info') IS NOT NULL").text(0, 0) != "t") return 0;
    const auto version = static_cast<int>(c.exec("SELECT version FROM ballbar.schema_info WHERE id = 1").integer(0, 0));
    if (version > kServerSchemaVersion)
        throw FleetError(FleetError::Kind::newer_schema, c.where() + " holds ballbar's server schema version " +
                                                             std::to_string(version) + ", newer than this ballbar's (" +
                                                             std::to_string(kServerSchemaVersion) +
                                                             "): " + std::string(advice));
    return version;
}

int ensure_server_schema(pg::Connection& c) {
    pg::Transaction t(c);
    c.exec("SELECT pg_advisory_xact_lock(" + std::to_string(kSchemaLockKey) + ")");
    const int version = server_schema_version(c, "a newer ballbar synced to it; update this station's ballbar");
    if (version == kServerSchemaVersion) {
        t.commit();
        return version;
    }
    // A DBA may have made the schema for an owner role without CREATE on the database (docs/fleet.md):
    // CREATE SCHEMA IF NOT EXISTS would still need that privilege.
    if (c.exec("SELECT count(*) FROM pg_namespace WHERE nspname = 'ballbar'").integer(0, 0) == 0)
        c.exec("CREATE SCHEMA ballbar");
    for (int v = version; v < kServerSchemaVersion; ++v) c.exec(detail::kServerMigrations[static_cast<std::size_t>(v)]);
    c.exec("UPDATE ballbar.schema_info SET version = " + std::to_string(kServerSchemaVersion) +
           ", migrated_at = now() WHERE id = 1");
    t.commit();
    return version;
}

SyncReport sync(storage::Store& station, pg::Connection& server, const SyncOptions& options) {
    return Syncer(station, server, options).run();
}

}  // namespace ballbar::fleet
