// SPDX-License-Identifier: MIT
// The fleet tests' server and oracles: a throwaway PostgreSQL (pg_throwaway.sh), psql and sqlite3 run as
// separate programs — the counts and checksums they compute are the tests' independent view of what is
// on the server and on the station.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

namespace ballbar::test {

/// A command's exit code and stdout (stderr too, appended after stdout with `with_err`).
struct Sh {
    int code = -1;
    std::string out;
};

inline Sh sh(const std::string& cmd) {
    Sh r;
    FILE* p = ::popen(cmd.c_str(), "r");
    if (!p) return r;
    char buf[65536];
    std::size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
    const int status = ::pclose(p);
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

inline std::string shq(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

/// `ENV ballbar --db DB ARGS`: its exit code, and its standard output and error together.
inline Sh ballbar_cli(const std::string& db, const std::string& args, const std::string& env = "") {
    return sh(env + " " + shq(BALLBAR_EXE) + " --db " + shq(db) + " " + args + " 2>&1");
}

/// The JSON document in a command's output (after any words it wrote on standard error); null when none.
inline nlohmann::json json_in(const Sh& r) {
    const auto at = r.out.find('{');
    return at == std::string::npos ? nlohmann::json() : nlohmann::json::parse(r.out.substr(at), nullptr, false);
}

/// A PostgreSQL server of this test's own, gone when it ends.
class PgServer {
  public:
    /// Starts it; `skip` is set (with why) where PostgreSQL is not installed.
    PgServer() {
        const Sh r = sh(std::string("bash ") + BALLBAR_PG_THROWAWAY + " start 2>&1");
        if (r.code == 77) {
            skip = r.out;
            return;
        }
        std::istringstream in(r.out);
        if (r.code != 0 || !(in >> dir >> port))
            throw std::runtime_error("the throwaway server did not start: " + r.out);
    }
    ~PgServer() {
        if (!dir.empty()) sh(std::string("bash ") + BALLBAR_PG_THROWAWAY + " stop " + shq(dir));
    }
    PgServer(const PgServer&) = delete;
    PgServer& operator=(const PgServer&) = delete;

    /// The superuser over the socket (no password).
    std::string super() const {
        return "host=" + dir + " port=" + std::to_string(port) + " user=postgres dbname=postgres";
    }
    /// A role with its password over TCP (the password is given in PGPASSWORD).
    std::string tcp(const std::string& role, int at_port = 0) const {
        return "host=127.0.0.1 port=" + std::to_string(at_port ? at_port : port) + " user=" + role + " dbname=postgres";
    }
    /// psql as the superuser: unaligned, tuples only, '|' between fields; stops at the first error.
    Sh psql(const std::string& sql) const {
        return sh("psql -X -q -v ON_ERROR_STOP=1 -At -F '|' " + shq(super()) + " -c " + shq(sql) + " 2>&1");
    }
    /// A server crash: an immediate stop (no checkpoint), and a start that recovers from the WAL.
    void crash() const { sh(std::string("bash ") + BALLBAR_PG_THROWAWAY + " crash " + shq(dir) + " 2>&1"); }

    std::string skip;
    std::string dir;
    int port = 0;
};

#define BALLBAR_NEED_SERVER(server) \
    if (!(server).skip.empty()) GTEST_SKIP() << "PostgreSQL's server is absent: " << (server).skip

/// sqlite3 on a station's file: unaligned, '|' between fields.
inline Sh sqlite(const std::string& db, const std::string& sql) {
    return sh("sqlite3 -bail -separator '|' " + shq(db) + " " + shq(sql) + " 2>&1");
}

/// Per session of a station: state, counts and sums of everything sent, one line a session by uuid.
inline std::string station_digest(const std::string& db, bool samples) {
    const std::string sample_sums =
        samples
            ? "(SELECT count(*) || '|' || coalesce(sum(displacement_nm), 0) || '|' || coalesce(sum(device_time_us), 0) "
              "|| '|' || coalesce(sum(flags), 0) || '|' || coalesce(sum(bar_temp_mC), 0) || '|' || coalesce(min(seq), "
              "-1) "
              "|| '|' || coalesce(max(seq), -1) FROM samples x WHERE x.session_id = s.id)"
            : "'-'";
    return sqlite(db,
                  "SELECT s.uuid, s.state, coalesce(s.ended_at, ''), s.notes, m.uuid, coalesce(m.asset_id, ''), "
                  "(SELECT count(*) || '|' || coalesce(sum(length(payload_json)), 0) FROM results r WHERE r.session_id "
                  "= s.id), "
                  "(SELECT count(*) || '|' || coalesce(sum(n), 0) || '|' || coalesce(sum(idx), 0) FROM points p WHERE "
                  "p.session_id = s.id), "
                  "(SELECT count(*) FROM session_transitions t WHERE t.session_id = s.id), "
                  "(SELECT count(*) FROM sample_segments g WHERE g.session_id = s.id), "
                  "(SELECT count(*) FROM sample_gaps g WHERE g.session_id = s.id), " +
                      sample_sums + " FROM sessions s JOIN machines m ON m.id = s.machine_id ORDER BY s.uuid")
        .out;
}

/// The same, computed by psql on the server, for one station's sessions.
inline std::string server_digest(const PgServer& pg, const std::string& station, bool samples) {
    const std::string sample_sums =
        samples
            ? "(SELECT count(*) || '|' || coalesce(sum(displacement_nm), 0) || '|' || coalesce(sum(device_time_us), 0) "
              "|| '|' || coalesce(sum(flags), 0) || '|' || coalesce(sum(bar_temp_mc), 0) || '|' || coalesce(min(seq), "
              "-1) "
              "|| '|' || coalesce(max(seq), -1) FROM ballbar.samples x WHERE x.session_uuid = s.uuid)"
            : "'-'";
    return pg
        .psql(
            "SELECT s.uuid, s.state, coalesce(s.ended_at, ''), s.notes, m.uuid, coalesce(m.asset_id, ''), "
            "(SELECT count(*) || '|' || coalesce(sum(length(payload_json)), 0) FROM ballbar.results r WHERE "
            "r.session_uuid = s.uuid), "
            "(SELECT count(*) || '|' || coalesce(sum(n), 0) || '|' || coalesce(sum(idx), 0) FROM ballbar.points p "
            "WHERE p.session_uuid = s.uuid), "
            "(SELECT count(*) FROM ballbar.session_transitions t WHERE t.session_uuid = s.uuid), "
            "(SELECT count(*) FROM ballbar.sample_segments g WHERE g.session_uuid = s.uuid), "
            "(SELECT count(*) FROM ballbar.sample_gaps g WHERE g.session_uuid = s.uuid), " +
            sample_sums +
            " FROM ballbar.sessions s JOIN ballbar.machines m ON m.uuid = s.machine_uuid WHERE s.station_uuid = '" +
            station + "' ORDER BY s.uuid")
        .out;
}

/// Every result's uuid, kind and document, byte for byte.
inline std::string station_results(const std::string& db) {
    return sqlite(db, "SELECT uuid, kind, producer, created_at, payload_json FROM results ORDER BY uuid").out;
}
inline std::string server_results(const PgServer& pg, const std::string& station) {
    return pg
        .psql(
            "SELECT r.uuid, r.kind, r.producer, r.created_at, r.payload_json FROM ballbar.results r JOIN "
            "ballbar.sessions s "
            "ON s.uuid = r.session_uuid WHERE s.station_uuid = '" +
            station + "' ORDER BY r.uuid")
        .out;
}

inline std::string station_uuid(const std::string& db) {
    std::string s = sqlite(db, "SELECT uuid FROM station").out;
    while (!s.empty() && s.back() == '\n') s.pop_back();
    return s;
}

}  // namespace ballbar::test
