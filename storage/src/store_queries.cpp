// SPDX-License-Identifier: MIT
// Store: reading sessions back, points, samples, results and models.
#include <algorithm>
#include <cmath>
#include <limits>

#include "ballbar/storage/machine_json.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::storage {
namespace {

using Kind = StorageError::Kind;

constexpr const char* kSessionSelect =
    "SELECT s.id, s.uuid, m.geometry_json, m.name, i.model, i.serial, i.firmware, i.calibrated_length_mm, "
    "i.calibration_date, i.extra_json, s.instrument_id, s.source, s.state, s.operator, s.procedure, s.notes, "
    "s.started_at, s.ended_at, s.metadata_json, "
    "(SELECT count(*) FROM samples WHERE session_id = s.id), (SELECT count(*) FROM points WHERE session_id = s.id) "
    "FROM sessions s JOIN machines m ON m.id = s.machine_id LEFT JOIN instruments i ON i.id = s.instrument_id ";

SessionInfo read_session(const Statement& st) {
    SessionInfo s;
    s.id = st.column_int(0);
    s.uuid = st.column_text(1);
    try {
        s.machine = machine_from_json(st.column_text(2));
    } catch (const FormatError& e) {
        throw StorageError(Kind::corrupt,
                           "session " + std::to_string(s.id) + ": stored machine unreadable: " + e.what());
    }
    s.machine.name = st.column_text(3);
    if (!st.is_null(10)) {
        Instrument in;
        in.model = st.column_text(4);
        in.serial = st.column_text(5);
        in.firmware = st.column_text(6);
        in.calibrated_length_mm = st.column_opt_double(7);
        in.calibration_date = st.column_text(8);
        in.extra_json = st.column_text(9);
        s.instrument = in;
    }
    s.source = parse_session_source(st.column_text(11)).value_or(SessionSource::device);
    s.state = parse_session_state(st.column_text(12)).value_or(SessionState::interrupted);
    s.operator_name = st.column_text(13);
    s.procedure = st.column_text(14);
    s.notes = st.column_text(15);
    s.started_at = st.column_text(16);
    s.ended_at = st.column_opt_text(17);
    s.metadata_json = st.column_text(18);
    s.sample_count = st.column_int(19);
    s.point_count = st.column_int(20);
    return s;
}

// SQLite integers are signed 64-bit; seqs and device times stay far below 2^63.
std::int64_t to_db(std::uint64_t v) {
    return static_cast<std::int64_t>(std::min<std::uint64_t>(v, std::numeric_limits<std::int64_t>::max()));
}

}  // namespace

void Store::annotate(SessionInfo& s) {
    if (schema_version_ >= 7) {
        auto a = db_.prepare(
            "SELECT coalesce(m.asset_id, '') FROM sessions s JOIN machines m ON m.id = s.machine_id WHERE s.id = ?");
        a.bind(1, s.id);
        if (a.step()) s.machine_asset = a.column_text(0);
    }
    if ((s.state == SessionState::created || s.state == SessionState::running) && !writer_alive(s.id)) {
        s.state = SessionState::interrupted;
        s.writer_gone = true;
        s.reason = "interrupted: its writer is gone (the process ended without finishing it)";
        return;
    }
    auto st = db_.prepare(schema_version_ >= 2 ? "SELECT event FROM session_transitions WHERE session_id = ? AND "
                                                 "scope = 'session' ORDER BY id DESC LIMIT 1"
                                               : "SELECT event FROM session_transitions WHERE session_id = ? "
                                                 "ORDER BY id DESC LIMIT 1");
    st.bind(1, s.id);
    if (st.step()) s.reason = st.column_text(0);
}

SessionInfo Store::session(std::int64_t id) {
    SessionInfo s;
    {
        auto st = db_.prepare(std::string(kSessionSelect) + "WHERE s.id = ?");
        st.bind(1, id);
        if (!st.step()) throw StorageError(Kind::not_found, "no session " + std::to_string(id));
        s = read_session(st);
    }
    annotate(s);
    return s;
}

std::vector<SessionInfo> Store::sessions() {
    std::vector<SessionInfo> out;
    {
        auto st = db_.prepare(std::string(kSessionSelect) + "ORDER BY s.id");
        while (st.step()) out.push_back(read_session(st));
    }
    for (auto& s : out) annotate(s);
    return out;
}

void Store::add_sample_gap(std::int64_t session_id, const SampleGap& g) {
    auto st = db_.prepare(
        "INSERT OR REPLACE INTO sample_gaps(session_id, before_seq, duration_s, cause) VALUES (?, ?, ?, ?)");
    st.bind(1, session_id).bind(2, to_db(g.before_seq)).bind(3, g.duration_s).bind(4, g.cause).run();
}

std::vector<SampleGap> Store::sample_gaps(std::int64_t session_id) {
    std::vector<SampleGap> out;
    if (schema_version_ < 6) return out;  // an older file opened read-only
    auto st =
        db_.prepare("SELECT before_seq, duration_s, cause FROM sample_gaps WHERE session_id = ? ORDER BY before_seq");
    st.bind(1, session_id);
    while (st.step()) {
        SampleGap g;
        g.before_seq = static_cast<std::uint64_t>(st.column_int(0));
        g.duration_s = st.column_opt_double(1);
        g.cause = st.column_text(2);
        out.push_back(std::move(g));
    }
    return out;
}

void Store::add_sample_segment(std::int64_t session_id, const SampleSegment& g) {
    auto st = db_.prepare(
        "INSERT OR REPLACE INTO sample_segments(session_id, first_seq, device_time_us, started_at) VALUES (?, ?, ?, "
        "?)");
    st.bind(1, session_id).bind(2, to_db(g.first_seq)).bind(3, to_db(g.device_time_us));
    st.bind(4, g.started_at.empty() ? now_iso8601() : g.started_at).run();
}

std::vector<SampleSegment> Store::sample_segments(std::int64_t session_id) {
    std::vector<SampleSegment> out;
    if (schema_version_ < 3) return out;  // an older file opened read-only
    auto st = db_.prepare(schema_version_ < 4 ? "SELECT first_seq, device_time_us, started_at, NULL, NULL FROM "
                                                "sample_segments WHERE session_id = ? ORDER BY first_seq"
                                              : "SELECT first_seq, device_time_us, started_at, resolution_mm, "
                                                "reading_rate_hz FROM sample_segments WHERE session_id = ? ORDER BY "
                                                "first_seq");
    st.bind(1, session_id);
    while (st.step()) {
        SampleSegment g;
        g.first_seq = static_cast<std::uint64_t>(st.column_int(0));
        g.device_time_us = static_cast<std::uint64_t>(st.column_int(1));
        g.started_at = st.column_text(2);
        g.resolution_mm = st.column_opt_double(3);
        g.reading_rate_hz = st.column_opt_double(4);
        out.push_back(std::move(g));
    }
    return out;
}

std::size_t Store::set_segment_instrument(std::int64_t session_id, std::uint64_t from_seq, double resolution_mm,
                                          double reading_rate_hz) {
    if (!(resolution_mm > 0) || !(reading_rate_hz > 0))
        throw StorageError(Kind::invalid, "a segment's resolution and reading rate must be > 0");
    auto st = db_.prepare(
        "UPDATE sample_segments SET resolution_mm = ?, reading_rate_hz = ? WHERE session_id = ? AND first_seq >= ?");
    st.bind(1, resolution_mm).bind(2, reading_rate_hz).bind(3, session_id).bind(4, to_db(from_seq)).run();
    return static_cast<std::size_t>(db_.changes());
}

std::optional<SampleSegment> Store::segment_of(std::int64_t session_id, std::uint64_t seq) {
    std::optional<SampleSegment> found;
    for (auto& g : sample_segments(session_id)) {
        if (g.first_seq > seq) break;
        found = std::move(g);
    }
    return found;
}

std::int64_t Store::find_session(std::string_view key) {
    if (key.empty()) throw StorageError(Kind::not_found, "no session given");
    const bool digits = std::all_of(key.begin(), key.end(), [](char c) { return c >= '0' && c <= '9'; });
    if (digits && key.size() < 18) {
        auto st = db_.prepare("SELECT id FROM sessions WHERE id = ?");
        st.bind(1, static_cast<std::int64_t>(std::stoll(std::string(key))));
        if (st.step()) return st.column_int(0);
    }
    // Digits shorter than a uuid's first group (8) are an id, never a uuid prefix: "99" must not find
    // (or resume) a session whose uuid happens to start with 99.
    if (digits && key.size() < 8) throw StorageError(Kind::not_found, "no session \"" + std::string(key) + "\"");
    std::string prefix;
    for (const char c : key) {
        const char l = (c >= 'A' && c <= 'F') ? static_cast<char>(c - 'A' + 'a') : c;
        if (!((l >= '0' && l <= '9') || (l >= 'a' && l <= 'f') || l == '-')) {
            throw StorageError(Kind::not_found,
                               "no session \"" + std::string(key) + "\" (give an id or a uuid prefix)");
        }
        prefix += l;
    }
    auto st = db_.prepare("SELECT id FROM sessions WHERE substr(uuid, 1, ?) = ? ORDER BY id LIMIT 2");
    st.bind(1, static_cast<std::int64_t>(prefix.size())).bind(2, prefix);
    if (!st.step()) throw StorageError(Kind::not_found, "no session \"" + std::string(key) + "\"");
    const std::int64_t id = st.column_int(0);
    if (st.step()) {
        throw StorageError(Kind::not_found, "session \"" + std::string(key) + "\" is ambiguous: give more of the uuid");
    }
    return id;
}

std::vector<Transition> Store::transitions(std::int64_t session_id) {
    auto st = db_.prepare(schema_version_ >= 2 ? "SELECT from_state, to_state, event, at FROM session_transitions "
                                                 "WHERE session_id = ? AND scope = 'session' ORDER BY id"
                                               : "SELECT from_state, to_state, event, at FROM session_transitions "
                                                 "WHERE session_id = ? ORDER BY id");  // v1, opened read-only
    st.bind(1, session_id);
    std::vector<Transition> out;
    while (st.step()) {
        Transition t;
        if (!st.is_null(0)) t.from = parse_session_state(st.column_text(0));
        t.to = parse_session_state(st.column_text(1)).value_or(SessionState::interrupted);
        t.event = st.column_text(2);
        t.at = st.column_text(3);
        out.push_back(std::move(t));
    }
    return out;
}

void Store::add_procedure_step(std::int64_t session_id, const ProcedureStep& step) {
    auto st = db_.prepare(
        "INSERT INTO session_transitions(session_id, from_state, to_state, event, at, scope, detail) "
        "VALUES (?, ?, ?, ?, ?, 'procedure', ?)");
    st.bind(1, session_id).bind(2, step.from).bind(3, step.to).bind(4, step.event);
    st.bind(5, step.at.empty() ? now_iso8601() : step.at).bind(6, step.detail).run();
}

std::vector<ProcedureStep> Store::procedure_steps(std::int64_t session_id) {
    // A v1 database opened read-only (not migrated) keeps them as results of kind
    // 'acquisition.transition', which results() returns.
    if (schema_version_ < 2) return {};
    auto st = db_.prepare(
        "SELECT from_state, to_state, event, detail, at FROM session_transitions WHERE session_id = ? AND scope = "
        "'procedure' ORDER BY id");
    st.bind(1, session_id);
    std::vector<ProcedureStep> out;
    while (st.step()) {
        ProcedureStep p;
        if (!st.is_null(0)) p.from = st.column_text(0);
        p.to = st.column_text(1);
        p.event = st.column_text(2);
        p.detail = st.column_text(3);
        p.at = st.column_text(4);
        out.push_back(std::move(p));
    }
    return out;
}

std::int64_t Store::sample_count(std::int64_t session_id) {
    auto st = db_.prepare("SELECT count(*) FROM samples WHERE session_id = ?");
    st.bind(1, session_id);
    st.step();
    return st.column_int(0);
}

std::uint64_t Store::next_seq(std::int64_t session_id) {
    auto st = db_.prepare("SELECT max(seq) FROM samples WHERE session_id = ?");
    st.bind(1, session_id);
    st.step();
    return st.is_null(0) ? 0 : static_cast<std::uint64_t>(st.column_int(0)) + 1;
}

void Store::for_each_sample(std::int64_t session_id, const std::function<void(const analysis::BarSample&)>& fn) {
    auto st = db_.prepare(
        "SELECT seq, device_time_us, displacement_nm, flags, bar_temp_mC FROM samples WHERE session_id = ? "
        "ORDER BY seq");
    st.bind(1, session_id);
    while (st.step()) {
        analysis::BarSample s;
        s.seq = static_cast<std::uint64_t>(st.column_int(0));
        s.device_time_us = static_cast<std::uint64_t>(st.column_int(1));
        s.displacement_nm = static_cast<std::int32_t>(st.column_int(2));
        s.flags = static_cast<std::uint16_t>(st.column_int(3));
        s.bar_temp_C = static_cast<float>(static_cast<double>(st.column_int(4)) / 1000.0);
        fn(s);
    }
}

std::vector<analysis::BarSample> Store::samples(std::int64_t session_id, std::uint64_t from_seq, std::size_t limit) {
    auto st = db_.prepare(
        "SELECT seq, device_time_us, displacement_nm, flags, bar_temp_mC FROM samples WHERE session_id = ? "
        "AND seq >= ? ORDER BY seq LIMIT ?");
    st.bind(1, session_id).bind(2, to_db(from_seq)).bind(3, to_db(limit));
    std::vector<analysis::BarSample> out;
    while (st.step()) {
        analysis::BarSample s;
        s.seq = static_cast<std::uint64_t>(st.column_int(0));
        s.device_time_us = static_cast<std::uint64_t>(st.column_int(1));
        s.displacement_nm = static_cast<std::int32_t>(st.column_int(2));
        s.flags = static_cast<std::uint16_t>(st.column_int(3));
        s.bar_temp_C = static_cast<float>(static_cast<double>(st.column_int(4)) / 1000.0);
        out.push_back(s);
    }
    return out;
}

namespace {

constexpr std::string_view kInsertPoint =
    "INSERT INTO points(session_id, idx, location, point, step, X_mm, Y_mm, Z_mm, A_rad, B_rad, C_rad, "
    "socket_x_mm, socket_y_mm, socket_z_mm, nominal_mm, mean_mm, std_mm, n, first_seq, last_seq, time_s, "
    "bar_temp_C, air_temp_C, machine_temp_C) VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?)";

void bind_point(Statement& st, std::int64_t session_id, std::int64_t idx, const PointRecord& p) {
    const auto& r = p.reading;
    st.bind(1, session_id).bind(2, idx).bind(3, r.location).bind(4, r.point).bind(5, r.step);
    st.bind(6, r.pose.X_mm).bind(7, r.pose.Y_mm).bind(8, r.pose.Z_mm);
    st.bind(9, r.pose.A_rad).bind(10, r.pose.B_rad).bind(11, r.pose.C_rad);
    st.bind(12, r.socket_mm.x()).bind(13, r.socket_mm.y()).bind(14, r.socket_mm.z());
    st.bind(15, p.nominal_mm).bind(16, r.measured_mm).bind(17, r.std_mm).bind(18, r.n);
    st.bind(19, p.first_seq ? std::optional<std::int64_t>(to_db(*p.first_seq)) : std::nullopt);
    st.bind(20, p.last_seq ? std::optional<std::int64_t>(to_db(*p.last_seq)) : std::nullopt);
    st.bind(21, r.time_s).bind(22, r.bar_temp_C).bind(23, r.air_temp_C).bind(24, r.machine_temp_C);
}

}  // namespace

std::int64_t Store::add_point(std::int64_t session_id, const PointRecord& p) {
    Transaction tx(db_);
    state_of(session_id);  // throws not_found
    auto next = db_.prepare("SELECT coalesce(max(idx) + 1, 0) FROM points WHERE session_id = ?");
    next.bind(1, session_id);
    next.step();
    const std::int64_t idx = next.column_int(0);
    auto st = db_.prepare(kInsertPoint);
    bind_point(st, session_id, idx, p);
    st.run();
    tx.commit();
    return idx;
}

void Store::add_points(std::int64_t session_id, const std::vector<PointRecord>& points) {
    if (points.empty()) return;
    Transaction tx(db_);
    state_of(session_id);  // throws not_found
    auto next = db_.prepare("SELECT coalesce(max(idx) + 1, 0) FROM points WHERE session_id = ?");
    next.bind(1, session_id);
    next.step();
    std::int64_t idx = next.column_int(0);
    auto st = db_.prepare(kInsertPoint);
    for (const auto& p : points) {
        bind_point(st, session_id, idx++, p);
        st.run();
    }
    tx.commit();
}

std::vector<PointRecord> Store::points(std::int64_t session_id) {
    auto st = db_.prepare(
        "SELECT idx, location, point, step, X_mm, Y_mm, Z_mm, A_rad, B_rad, C_rad, socket_x_mm, socket_y_mm, "
        "socket_z_mm, nominal_mm, mean_mm, std_mm, n, first_seq, last_seq, time_s, bar_temp_C, air_temp_C, "
        "machine_temp_C FROM points WHERE session_id = ? ORDER BY idx");
    st.bind(1, session_id);
    std::vector<PointRecord> out;
    while (st.step()) {
        PointRecord p;
        auto& r = p.reading;
        p.index = st.column_int(0);
        r.location = static_cast<int>(st.column_int(1));
        r.point = static_cast<int>(st.column_int(2));
        r.step = static_cast<int>(st.column_int(3));
        r.pose = {st.column_double(4), st.column_double(5), st.column_double(6),
                  st.column_double(7), st.column_double(8), st.column_double(9)};
        r.socket_mm = {st.column_double(10), st.column_double(11), st.column_double(12)};
        p.nominal_mm = st.column_double(13);
        r.measured_mm = st.column_double(14);
        r.std_mm = st.column_opt_double(15);
        r.n = static_cast<int>(st.column_int(16));
        if (!st.is_null(17)) p.first_seq = static_cast<std::uint64_t>(st.column_int(17));
        if (!st.is_null(18)) p.last_seq = static_cast<std::uint64_t>(st.column_int(18));
        r.time_s = st.column_double(19);
        r.bar_temp_C = st.column_opt_double(20);
        r.air_temp_C = st.column_opt_double(21);
        r.machine_temp_C = st.column_opt_double(22);
        out.push_back(std::move(p));
    }
    return out;
}

std::int64_t Store::add_result(std::int64_t session_id, std::string_view kind, std::string_view payload_json,
                               std::optional<std::int64_t> model_id, std::string_view producer) {
    Transaction tx(db_);
    state_of(session_id);
    auto st = db_.prepare(
        "INSERT INTO results(session_id, kind, payload_json, model_id, producer, created_at, uuid) "
        "VALUES (?,?,?,?,?,?,?)");
    st.bind(1, session_id).bind(2, kind).bind(3, payload_json).bind(4, model_id).bind(5, producer);
    st.bind(6, now_iso8601()).bind(7, new_uuid()).run();
    const std::int64_t id = db_.last_insert_rowid();
    tx.commit();
    return id;
}

std::vector<ResultRecord> Store::results(std::int64_t session_id) {
    auto st = db_.prepare(
        "SELECT id, session_id, kind, payload_json, model_id, producer, created_at FROM results WHERE session_id = ? "
        "ORDER BY id");
    st.bind(1, session_id);
    std::vector<ResultRecord> out;
    while (st.step()) {
        out.push_back({st.column_int(0), st.column_int(1), st.column_text(2), st.column_text(3), st.column_opt_int(4),
                       st.column_text(5), st.column_text(6)});
    }
    return out;
}

/// The columns read_model reads, in its order.
constexpr std::string_view kModelSelect =
    "SELECT id, name, version, parent_id, params_json, notes, created_at FROM models ";

ModelRecord Store::read_model(Statement& st) {
    ModelRecord m;
    m.id = st.column_int(0);
    m.name = st.column_text(1);
    m.version = static_cast<int>(st.column_int(2));
    m.parent_id = st.column_opt_int(3);
    m.params_json = st.column_text(4);
    m.notes = st.column_text(5);
    m.created_at = st.column_text(6);
    auto ss = db_.prepare("SELECT session_id FROM model_sessions WHERE model_id = ? ORDER BY session_id");
    ss.bind(1, m.id);
    while (ss.step()) m.session_ids.push_back(ss.column_int(0));
    return m;
}

ModelRecord Store::save_model(std::string_view name, std::string_view params_json,
                              const std::vector<std::int64_t>& session_ids, std::optional<std::int64_t> parent_id,
                              std::string_view notes) {
    if (name.empty()) throw StorageError(Kind::invalid, "a model needs a name");
    Transaction tx(db_);
    auto next = db_.prepare("SELECT coalesce(max(version), 0) + 1 FROM models WHERE name = ?");
    next.bind(1, name);
    next.step();
    const std::int64_t version = next.column_int(0);
    auto st = db_.prepare(
        "INSERT INTO models(name, version, parent_id, params_json, notes, created_at, uuid) VALUES (?,?,?,?,?,?,?)");
    st.bind(1, name).bind(2, version).bind(3, parent_id).bind(4, params_json).bind(5, notes);
    st.bind(6, now_iso8601()).bind(7, new_uuid()).run();
    const std::int64_t id = db_.last_insert_rowid();
    auto link = db_.prepare("INSERT OR IGNORE INTO model_sessions(model_id, session_id) VALUES (?, ?)");
    for (const auto sid : session_ids) {
        link.bind(1, id).bind(2, sid).run();
    }
    tx.commit();
    return model(id);
}

ModelRecord Store::model(std::int64_t model_id) {
    auto st = db_.prepare(std::string(kModelSelect) + "WHERE id = ?");
    st.bind(1, model_id);
    if (!st.step()) throw StorageError(Kind::not_found, "no model " + std::to_string(model_id));
    return read_model(st);
}

std::vector<ModelRecord> Store::model_history(std::string_view name) {
    auto st = db_.prepare(std::string(kModelSelect) + "WHERE name = ? ORDER BY version");
    st.bind(1, name);
    std::vector<ModelRecord> out;
    while (st.step()) out.push_back(read_model(st));
    return out;
}

std::optional<ModelRecord> Store::latest_model(std::string_view name) {
    auto st = db_.prepare(std::string(kModelSelect) + "WHERE name = ? ORDER BY version DESC LIMIT 1");
    st.bind(1, name);
    if (!st.step()) return std::nullopt;
    return read_model(st);
}

}  // namespace ballbar::storage
