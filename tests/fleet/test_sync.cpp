// SPDX-License-Identifier: MIT
// `ballbar sync` against a real PostgreSQL server (docs/fleet.md): two stations into one server, checked
// by psql against sqlite3 on each station; a second sync writes nothing; a station's role that may only
// read, insert and update; a uuid of another station is a conflict, reported and not merged.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "../app/json_vocabulary.hpp"
#include "../scratch_dir.hpp"
#include "pg_fixture.hpp"

namespace {

using ballbar::test::json_in;
using ballbar::test::PgServer;
using ballbar::test::ScratchDir;
using ballbar::test::sh;
using ballbar::test::shq;
using nlohmann::json;

const std::string kMachines = std::string(BALLBAR_TEST_DATA_DIR) + "/machines/";

json sync_json(const std::string& db, const std::string& conninfo, const std::string& env = "",
               const std::string& more = " --samples") {
    const auto r = ballbar::test::ballbar_cli(db, "sync " + shq(conninfo) + more + " --json", env);
    EXPECT_EQ(r.code, 0) << r.out;
    return json_in(r);
}

/// Everything on the server as one checksum: a sync that changes nothing leaves it as it was (times included).
std::string server_fingerprint(const PgServer& pg) {
    std::string all;
    for (const char* t : {"stations", "machines", "models", "sessions", "session_transitions", "points", "results",
                          "model_sessions", "sample_segments", "sample_gaps", "samples", "schema_info"})
        all += pg.psql(std::string(
                           "SELECT count(*) || ':' || coalesce(md5(string_agg(t::text, ',' ORDER BY t::text)), '') "
                           "FROM ballbar.") +
                       t + " t")
                   .out;
    return all;
}

void measure_station(const std::string& db, bool registered, int seed) {
    if (registered) {
        const auto add = ballbar::test::ballbar_cli(
            db, "machines add M-0042 --machine " + shq(kMachines + "tttrr.json") + " --location 'hall 2'");
        ASSERT_EQ(add.code, 0) << add.out;
        const auto demo = ballbar::test::ballbar_cli(db, "demo --asset M-0042 --seed " + std::to_string(seed));
        ASSERT_EQ(demo.code, 0) << demo.out;
    } else {
        const auto demo = ballbar::test::ballbar_cli(db, "demo --machine RRTTT --seed " + std::to_string(seed));
        ASSERT_EQ(demo.code, 0) << demo.out;
    }
    const auto circle =
        ballbar::test::ballbar_cli(db, "demo --test circular --plane XY --seed " + std::to_string(seed));
    ASSERT_EQ(circle.code, 0) << circle.out;
}

TEST(PgSync, TwoStationsSyncToOneServerAndEachStationsRecordsAreThereExactly) {
    PgServer pg;
    BALLBAR_NEED_SERVER(pg);
    ScratchDir d("fleet");
    const std::string a = d.file("a.db"), b = d.file("b.db");
    measure_station(a, true, 1);
    measure_station(b, false, 2);
    for (int i = 0; i < 2; ++i) {  // two versions of a model identified from a's SSM session
        const auto identified = ballbar::test::ballbar_cli(a, "identify 1 --name mill-a");
        ASSERT_EQ(identified.code, 0) << identified.out;
    }

    // Station a as the database's owner: it creates ballbar's schema.
    const json first = sync_json(a, pg.super());
    EXPECT_EQ(first.at("server_schema_created"), true);
    EXPECT_EQ(first.at("sessions_sent"), 2);
    EXPECT_EQ(first.at("rows").at("models"), 2);
    EXPECT_GT(first.at("rows").at("samples").get<long>(), 10000);
    EXPECT_EQ(first.at("conflicts"), json::array());
    EXPECT_EQ(ballbar::test::vocabulary_violations(first), std::vector<std::string>{}) << first.dump(2);

    // Station b as a role that may only read, insert and update (docs/fleet.md's SQL), with its password
    // from the environment, over TCP.
    ASSERT_EQ(pg.psql("CREATE ROLE station_b LOGIN PASSWORD 'b-secret'; GRANT USAGE ON SCHEMA ballbar TO station_b; "
                      "GRANT SELECT, INSERT, UPDATE ON ALL TABLES IN SCHEMA ballbar TO station_b;")
                  .code,
              0);
    const json second = sync_json(b, pg.tcp("station_b"), "PGPASSWORD=b-secret");
    EXPECT_EQ(second.at("server_schema_created"), false);
    EXPECT_EQ(second.at("sessions_sent"), 2);
    EXPECT_EQ(pg.psql("SET ROLE station_b; DELETE FROM ballbar.samples").code != 0, true) << "the role cannot delete";

    for (const std::string& db : {a, b}) {
        const std::string station = ballbar::test::station_uuid(db);
        const std::string local = ballbar::test::station_digest(db, true);
        EXPECT_EQ(std::count(local.begin(), local.end(), '\n'), 2) << local;
        EXPECT_EQ(ballbar::test::server_digest(pg, station, true), local);
        EXPECT_EQ(ballbar::test::server_results(pg, station), ballbar::test::station_results(db));
    }
    EXPECT_EQ(pg.psql("SELECT asset_id FROM ballbar.machines WHERE asset_id IS NOT NULL").out, "M-0042\n");
    // The models, byte for byte, with the sessions they were identified from.
    EXPECT_EQ(pg.psql("SELECT m.uuid, m.name, m.version, m.created_at, m.params_json, s.uuid FROM ballbar.models m "
                      "JOIN ballbar.model_sessions x ON x.model_uuid = m.uuid JOIN ballbar.sessions s ON s.uuid = "
                      "x.session_uuid ORDER BY m.uuid")
                  .out,
              ballbar::test::sqlite(a,
                                    "SELECT m.uuid, m.name, m.version, m.created_at, m.params_json, s.uuid FROM "
                                    "models m JOIN model_sessions x ON x.model_id = m.id JOIN sessions s ON s.id = "
                                    "x.session_id ORDER BY m.uuid")
                  .out);
    EXPECT_EQ(pg.psql("SELECT count(*) FROM ballbar.models").out, "2\n");
    EXPECT_EQ(
        pg.psql("SELECT count(*) FROM ballbar.results WHERE kind = 'identification' AND model_uuid IS NOT NULL").out,
        "2\n");

    // Again: nothing is new, nothing is written, not even a time.
    const std::string before = server_fingerprint(pg);
    for (const auto& [db, conn, env] : {std::tuple{a, pg.super(), std::string()},
                                        std::tuple{b, pg.tcp("station_b"), std::string("PGPASSWORD=b-secret")}}) {
        const json again = sync_json(db, conn, env);
        EXPECT_EQ(again.at("rows_written"), 0) << again.dump();
        EXPECT_EQ(again.at("sessions_sent"), 0);
    }
    EXPECT_EQ(server_fingerprint(pg), before);

    // A new session on a, notes on an old one: exactly that goes.
    const auto demo = ballbar::test::ballbar_cli(a, "demo --asset M-0042 --seed 3");
    ASSERT_EQ(demo.code, 0) << demo.out;
    ASSERT_EQ(ballbar::test::sqlite(a, "UPDATE sessions SET notes = 'probe re-seated' WHERE id = 1").code, 0);
    const json third = sync_json(a, pg.super(), "", "");  // results and models only, this time
    EXPECT_EQ(third.at("sessions_sent"), 2);
    EXPECT_EQ(third.at("rows").at("samples"), 0);
    const std::string station_a = ballbar::test::station_uuid(a);
    EXPECT_EQ(ballbar::test::server_digest(pg, station_a, false), ballbar::test::station_digest(a, false));
    EXPECT_EQ(pg.psql("SELECT notes FROM ballbar.sessions ORDER BY started_at LIMIT 1").out, "probe re-seated\n");
    const json samples = sync_json(a, pg.super());
    EXPECT_EQ(samples.at("sessions_sent"), 1) << "the new session's samples";
    EXPECT_EQ(ballbar::test::server_digest(pg, station_a, true), ballbar::test::station_digest(a, true));
}

TEST(PgSync, AnIdOfAnotherStationIsAConflictReportedNotMerged) {
    PgServer pg;
    BALLBAR_NEED_SERVER(pg);
    ScratchDir d("fleet");
    const std::string a = d.file("a.db"), copy = d.file("copy.db");
    const auto demo = ballbar::test::ballbar_cli(a, "demo --test circular --plane XY --seed 4");
    ASSERT_EQ(demo.code, 0) << demo.out;
    ASSERT_EQ(sync_json(a, pg.super()).at("sessions_sent"), 1);
    // A station made by copying another's file, then given its own id: its session's uuid is a's.
    std::filesystem::copy_file(a, copy);
    ASSERT_EQ(ballbar::test::sqlite(copy,
                                    "UPDATE station SET uuid = '00000000-0000-4000-8000-000000000001'; "
                                    "UPDATE sessions SET notes = 'copied'")
                  .code,
              0);
    const std::string machines = pg.psql("SELECT md5(string_agg(t::text, ',')) FROM ballbar.machines t").out;
    const auto r = ballbar::test::ballbar_cli(copy, "sync " + shq(pg.super()) + " --samples");
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find("under another station"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("session " + ballbar::test::sqlite(a, "SELECT uuid FROM sessions").out.substr(0, 36)),
              std::string::npos)
        << r.out;
    EXPECT_EQ(pg.psql("SELECT notes FROM ballbar.sessions").out,
              ballbar::test::sqlite(a, "SELECT notes FROM sessions").out)
        << "a's session is not overwritten";
    EXPECT_NE(pg.psql("SELECT notes FROM ballbar.sessions").out, "copied\n");
    EXPECT_EQ(pg.psql("SELECT count(*) FROM ballbar.sessions").out, "1\n");
    // The copy's station row was added (it is a station), nothing of a's was touched.
    EXPECT_EQ(pg.psql("SELECT count(*) FROM ballbar.stations").out, "2\n");
    EXPECT_EQ(pg.psql("SELECT md5(string_agg(t::text, ',')) FROM ballbar.machines t").out, machines);
}

TEST(PgSync, StationsSyncingAtOnceAndOneStationTwiceAtOnceLoseAndDuplicateNothing) {
    PgServer pg;
    BALLBAR_NEED_SERVER(pg);
    ScratchDir d("fleet");
    const std::string a = d.file("a.db"), b = d.file("b.db"), c = d.file("c.db");
    for (const auto& [db, seed] : {std::pair{a, 21}, std::pair{b, 22}, std::pair{c, 23}}) {
        const auto demo =
            ballbar::test::ballbar_cli(db, "demo --test circular --plane XY --seed " + std::to_string(seed));
        ASSERT_EQ(demo.code, 0) << demo.out;
    }
    // Four syncs at once into a server with no schema yet: a twice, b, c; small chunks so they interleave.
    std::string cmd;
    for (const std::string& db : {a, a, b, c})
        cmd += shq(BALLBAR_EXE) + " --db " + shq(db) + " sync " + shq(pg.super()) +
               " --samples --chunk 1000 >/dev/null 2>&1 & ";
    cmd += "for j in $(jobs -p); do wait $j || exit 1; done";
    const auto all = sh("bash -c " + shq(cmd));
    EXPECT_EQ(all.code, 0) << all.out;
    EXPECT_EQ(pg.psql("SELECT count(*) FROM ballbar.stations").out, "3\n");
    for (const std::string& db : {a, b, c}) {
        const std::string station = ballbar::test::station_uuid(db);
        EXPECT_EQ(ballbar::test::server_digest(pg, station, true), ballbar::test::station_digest(db, true));
        EXPECT_EQ(sync_json(db, pg.super()).at("rows_written"), 0);
    }
}

}  // namespace
