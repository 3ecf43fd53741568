// SPDX-License-Identifier: MIT
// Schema migrations on real old databases: a v1 file (made with v1's own schema text) opened by this
// version is migrated in place, loses nothing and keeps working.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "ballbar/storage/imports.hpp"
#include "ballbar/storage/machine_json.hpp"
#include "ballbar/storage/sqlite.hpp"
#include "ballbar/storage/store.hpp"
#include "schema.hpp"  // storage/src: the migrations as the store applies them
#include "test_util.hpp"

namespace ballbar::storage {
namespace {

using test::TempDir;

// A database exactly as schema v1 left it: one running session with two procedure steps stored as
// results of kind 'acquisition.transition' (v1's way), one malformed such result, and an SSM result.
void make_v1(const std::string& path) {
    Database db(path);
    db.exec("BEGIN");
    db.exec(detail::kMigrations[0]);
    db.exec("PRAGMA user_version = 1");
    db.exec("PRAGMA application_id = " + std::to_string(Store::kApplicationId));
    db.exec(R"sql(
INSERT INTO machines(id, name, type, geometry_json) VALUES (1, 'm', 'TTTRR', '{"type":"TTTRR"}');
INSERT INTO sessions(id, uuid, machine_id, source, state, started_at)
  VALUES (1, '11111111-1111-4111-8111-111111111111', 1, 'emulator', 'completed', '2026-11-01T10:00:00.000Z');
INSERT INTO session_transitions(session_id, from_state, to_state, event, at) VALUES
  (1, NULL, 'created', 'create', '2026-11-01T10:00:00.000Z'),
  (1, 'created', 'running', 'start', '2026-11-01T10:00:00.001Z'),
  (1, 'running', 'completed', 'finish', '2026-11-01T10:05:00.000Z');
INSERT INTO results(id, session_id, kind, payload_json, producer, created_at) VALUES
  (1, 1, 'acquisition.transition',
   '{"from":"Connecting","to":"CheckingInstrument","event":"Connected","detail":"emulator"}',
   'ballbar acquisition/1', '2026-11-01T10:00:01.000Z'),
  (2, 1, 'ssm', '{"test":1}', 'ballbar acquisition/1', '2026-11-01T10:01:00.000Z'),
  (3, 1, 'acquisition.transition',
   '{"from":"Step1Positioning","to":"Step1Capture","event":"InPosition","detail":"test 1 step 1 point 1"}',
   'ballbar acquisition/1', '2026-11-01T10:02:00.000Z'),
  (4, 1, 'acquisition.transition', 'not json', 'someone else', '2026-11-01T10:03:00.000Z');
)sql");
    db.exec("COMMIT");
}

// A database exactly as schema v3 left it: session 1 measured on a gauge (two segments: a connection
// and a resume), its resolution and rate written once as the `instrument` result (v3's way); session 2
// on the project's instrument (no instrument result); a stray non-JSON instrument result on session 2.
void make_v3(const std::string& path) {
    Database db(path);
    db.exec("BEGIN");
    for (int v = 0; v < 3; ++v) db.exec(detail::kMigrations[static_cast<std::size_t>(v)]);
    db.exec("PRAGMA user_version = 3");
    db.exec("PRAGMA application_id = " + std::to_string(Store::kApplicationId));
    db.exec(R"sql(
INSERT INTO machines(id, name, type, geometry_json) VALUES (1, 'm', 'TTTRR', '{"type":"TTTRR"}');
INSERT INTO sessions(id, uuid, machine_id, source, state, started_at) VALUES
  (1, '33333333-3333-4333-8333-333333333331', 1, 'device', 'completed', '2026-11-01T10:00:00.000Z'),
  (2, '33333333-3333-4333-8333-333333333332', 1, 'device', 'completed', '2026-11-01T11:00:00.000Z');
INSERT INTO samples(session_id, seq, device_time_us, displacement_nm, flags, bar_temp_mC) VALUES
  (1, 0, 1000, 10, 0, 20000), (1, 1, 51000, 11, 0, 20000), (1, 2, 101000, 12, 0, 20000),
  (1, 3, 5000, 13, 0, 20000), (1, 4, 55000, 14, 0, 20000),
  (2, 0, 0, 1, 0, 20000), (2, 1, 1000, 2, 0, 20000);
INSERT INTO sample_segments(session_id, first_seq, device_time_us, started_at) VALUES
  (1, 0, 1000, '2026-11-01T10:00:01.000Z'), (1, 3, 5000, '2026-11-01T10:30:00.000Z'),
  (2, 0, 0, '2026-11-01T11:00:01.000Z');
INSERT INTO results(id, session_id, kind, payload_json, producer, created_at) VALUES
  (1, 1, 'instrument', '{"kind":"sylvac","resolution_mm":0.001,"reading_rate_hz":19.8}', 'ballbar gauge/1',
   '2026-11-01T10:40:00.000Z'),
  (2, 2, 'instrument', 'not json', 'someone else', '2026-11-01T11:10:00.000Z');
)sql");
    db.exec("COMMIT");
}

TEST(Migration, V3GaugeSessionsGetTheirResolutionAndRateOnEverySample) {
    TempDir dir;
    const std::string path = dir.file("v3.db");
    make_v3(path);
    Store store(path);
    EXPECT_EQ(store.db().query_int("PRAGMA user_version"), Store::kSchemaVersion);
    EXPECT_EQ(store.integrity_check(), "ok");

    const auto segs = store.sample_segments(1);
    ASSERT_EQ(segs.size(), 2u);
    for (const auto& g : segs) {
        ASSERT_TRUE(g.resolution_mm && g.reading_rate_hz);
        EXPECT_DOUBLE_EQ(*g.resolution_mm, 0.001);
        EXPECT_DOUBLE_EQ(*g.reading_rate_hz, 19.8);
    }
    EXPECT_EQ(segs[1].started_at, "2026-11-01T10:30:00.000Z") << "the v3 columns are kept";
    for (std::uint64_t seq = 0; seq < 5; ++seq) {
        const auto g = store.segment_of(1, seq);
        ASSERT_TRUE(g) << seq;
        EXPECT_EQ(g->first_seq, seq < 3 ? 0u : 3u) << seq;
        EXPECT_DOUBLE_EQ(g->resolution_mm.value_or(0), 0.001) << seq;
    }
    // Per sample in SQL, through the view.
    auto st = store.db().prepare(
        "SELECT seq, segment_first_seq, resolution_mm, reading_rate_hz FROM sample_instruments WHERE session_id = 1 "
        "ORDER BY seq");
    int rows = 0;
    while (st.step()) {
        EXPECT_EQ(st.column_int(1), st.column_int(0) < 3 ? 0 : 3);
        EXPECT_DOUBLE_EQ(st.column_double(2), 0.001);
        EXPECT_DOUBLE_EQ(st.column_double(3), 19.8);
        ++rows;
    }
    EXPECT_EQ(rows, 5);

    // Not a gauge's session (its instrument result unreadable): not known, rather than guessed.
    const auto other = store.segment_of(2, 1);
    ASSERT_TRUE(other);
    EXPECT_FALSE(other->resolution_mm);
    EXPECT_FALSE(other->reading_rate_hz);
    EXPECT_EQ(store.results(2).size(), 1u) << "the migration changes no result";

    // The migrated file takes new figures.
    EXPECT_EQ(store.set_segment_instrument(2, 0, 1e-4, 40.0), 1u);
    EXPECT_DOUBLE_EQ(store.segment_of(2, 1)->reading_rate_hz.value_or(0), 40.0);
}

TEST(Migration, V3OpenedReadOnlyReadsSegmentsWithoutTheInstrumentFigures) {
    TempDir dir;
    const std::string path = dir.file("v3ro.db");
    make_v3(path);
    {
        StoreOptions ro;
        ro.read_only = true;
        Store store(path, ro);
        EXPECT_EQ(store.schema_version(), 3);
        const auto segs = store.sample_segments(1);
        ASSERT_EQ(segs.size(), 2u);
        EXPECT_FALSE(segs[0].resolution_mm);
    }
    Database db(path);
    EXPECT_EQ(db.query_int("PRAGMA user_version"), 3) << "a read-only open migrates nothing";
}

TEST(Migration, V1ProcedureStepsMoveIntoTheTransitionsTable) {
    TempDir dir;
    const std::string path = dir.file("v1.db");
    make_v1(path);
    Store store(path);
    EXPECT_EQ(store.db().query_int("PRAGMA user_version"), Store::kSchemaVersion);
    EXPECT_EQ(store.integrity_check(), "ok");

    const auto steps = store.procedure_steps(1);
    ASSERT_EQ(steps.size(), 2u);
    EXPECT_EQ(steps[0].from, "Connecting");
    EXPECT_EQ(steps[0].to, "CheckingInstrument");
    EXPECT_EQ(steps[0].event, "Connected");
    EXPECT_EQ(steps[0].detail, "emulator");
    EXPECT_EQ(steps[0].at, "2026-11-01T10:00:01.000Z");
    EXPECT_EQ(steps[1].to, "Step1Capture");
    EXPECT_EQ(steps[1].detail, "test 1 step 1 point 1");

    // The lifecycle is as it was; of the results, the moved ones are gone, the rest kept (a payload
    // the migration cannot read stays where it was rather than being lost).
    const auto life = store.transitions(1);
    ASSERT_EQ(life.size(), 3u);
    EXPECT_EQ(life.back().to, SessionState::completed);
    const auto results = store.results(1);
    ASSERT_EQ(results.size(), 2u);
    EXPECT_EQ(results[0].kind, "ssm");
    EXPECT_EQ(results[1].payload_json, "not json");

    // And the migrated database takes new steps after the old ones.
    store.add_procedure_step(1, {"Computing", "Review", "AllTestsDone", "", ""});
    const auto after = store.procedure_steps(1);
    ASSERT_EQ(after.size(), 3u);
    EXPECT_EQ(after.back().event, "AllTestsDone");
    EXPECT_FALSE(after.back().at.empty());
}

TEST(Migration, V1OpenedReadOnlyIsReadAsItIsAndNotChanged) {
    TempDir dir;
    const std::string path = dir.file("v1.db");
    make_v1(path);
    {
        StoreOptions ro;
        ro.read_only = true;
        Store store(path, ro);
        EXPECT_EQ(store.schema_version(), 1);
        EXPECT_EQ(store.transitions(1).size(), 3u);     // no scope column to filter on
        EXPECT_TRUE(store.procedure_steps(1).empty());  // v1 keeps them as results ...
        EXPECT_EQ(store.results(1).size(), 4u);         // ... which are all still there
        EXPECT_EQ(store.results(1)[0].kind, "acquisition.transition");
    }
    Database db(path);
    EXPECT_EQ(db.query_int("PRAGMA user_version"), 1) << "a read-only open migrates nothing";
}

// A database exactly as schema v4 left it: one imported session (v4 recorded no file hash).
void make_v4(const std::string& path) {
    Database db(path);
    db.exec("BEGIN");
    for (int v = 0; v < 4; ++v) db.exec(detail::kMigrations[static_cast<std::size_t>(v)]);
    db.exec("PRAGMA user_version = 4");
    db.exec("PRAGMA application_id = " + std::to_string(Store::kApplicationId));
    analysis::MachineGeometry m;
    m.type = analysis::MachineType::TTTRR;
    auto st = db.prepare("INSERT INTO machines(id, name, type, geometry_json) VALUES (1, 'm', 'TTTRR', ?)");
    st.bind(1, machine_to_json(m)).run();
    db.exec(R"sql(
INSERT INTO sessions(id, uuid, machine_id, source, state, procedure, started_at) VALUES
  (1, '44444444-4444-4444-8444-444444444441', 1, 'imported', 'completed', 'import', '2026-11-01T10:00:00.000Z');
)sql");
    db.exec("COMMIT");
}

TEST(Migration, V4GetsTheImportsTableAndItsImportedSessionNoRecordedFile) {
    TempDir dir;
    const std::string path = dir.file("v4.db");
    make_v4(path);
    {
        StoreOptions ro;
        ro.read_only = true;
        Store store(path, ro);
        EXPECT_EQ(store.schema_version(), 4);
        EXPECT_FALSE(import_of(store, 1)) << "read-only below v5: nothing to read, no error";
        EXPECT_TRUE(imports_of_content(store, sha256_hex("x")).empty());
    }
    Store store(path);
    EXPECT_EQ(store.db().query_int("PRAGMA user_version"), Store::kSchemaVersion);
    EXPECT_EQ(store.integrity_check(), "ok");
    EXPECT_EQ(store.session(1).source, SessionSource::imported) << "the session is kept";
    EXPECT_FALSE(import_of(store, 1)) << "imported before v5: its file is not known";
    record_import(store, 1, sha256_hex("readings"), "a.readings", 8);
    ASSERT_EQ(imports_of_content(store, sha256_hex("readings")).size(), 1u);
    EXPECT_EQ(import_of(store, 1)->file_name, "a.readings");
    EXPECT_THROW(record_import(store, 1, "not a hash", "b.readings", 1), StorageError) << "the CHECK holds";
}

// A database exactly as schema v5 left it: v4's, with the imports table.
TEST(Migration, V5GetsTheGapsTableAndItsSessionsNoRecordedGaps) {
    TempDir dir;
    const std::string path = dir.file("v5.db");
    make_v4(path);
    {
        Database db(path);
        db.exec("BEGIN");
        db.exec(detail::kMigrations[4]);
        db.exec("PRAGMA user_version = 5");
        db.exec("COMMIT");
    }
    {
        StoreOptions ro;
        ro.read_only = true;
        Store store(path, ro);
        EXPECT_EQ(store.schema_version(), 5);
        EXPECT_TRUE(store.sample_gaps(1).empty()) << "read-only below v6: nothing to read, no error";
    }
    Store store(path);
    EXPECT_EQ(store.db().query_int("PRAGMA user_version"), Store::kSchemaVersion);
    EXPECT_EQ(store.integrity_check(), "ok");
    EXPECT_TRUE(store.sample_gaps(1).empty()) << "stored before v6: its gaps were not kept";
    store.add_sample_gap(1, SampleGap{10, 0.25, "lost frames"});
    ASSERT_EQ(store.sample_gaps(1).size(), 1u);
    EXPECT_EQ(store.sample_gaps(1)[0].before_seq, 10u);
}

bool is_v4_uuid(const std::string& u) {
    if (u.size() != 36 || u[8] != '-' || u[13] != '-' || u[18] != '-' || u[23] != '-' || u[14] != '4') return false;
    return std::string("89ab").find(u[19]) != std::string::npos &&
           u.find_first_not_of("0123456789abcdef-") == std::string::npos;
}

// Every earlier version reaches v7 (the fleet's identities): its machines, models and results get
// uuids of their own, each machine stays the one its sessions were measured on (the machines table is
// rebuilt), the file gets a station id, and sessions keep their uuids.
class FromEveryVersion : public ::testing::TestWithParam<int> {};

TEST_P(FromEveryVersion, TheMachinesModelsAndResultsGetUuidsAndTheSessionsKeepTheirMachines) {
    const int version = GetParam();
    TempDir dir;
    const std::string path = dir.file("old.db");
    const std::string g1 = machine_to_json(test::tttrr()), g2 = [] {
        auto g = test::tttrr();
        g.tool_ball_mm.z() += 10;
        return machine_to_json(g);
    }();
    {
        Database db(path);
        db.exec("BEGIN");
        for (int v = 0; v < version; ++v) db.exec(detail::kMigrations[static_cast<std::size_t>(v)]);
        db.exec("PRAGMA user_version = " + std::to_string(version));
        db.exec("PRAGMA application_id = " + std::to_string(Store::kApplicationId));
        auto m = db.prepare("INSERT INTO machines(id, name, type, geometry_json) VALUES (?, ?, 'TTTRR', ?)");
        m.bind(1, 7).bind(2, "mill-1").bind(3, g1).run();
        auto m2 = db.prepare("INSERT INTO machines(id, name, type, geometry_json) VALUES (?, ?, 'TTTRR', ?)");
        m2.bind(1, 9).bind(2, "mill-2").bind(3, g2).run();
        db.exec(R"sql(
INSERT INTO sessions(id, uuid, machine_id, source, state, started_at) VALUES
  (1, '11111111-1111-4111-8111-111111111111', 9, 'emulator', 'completed', '2026-11-01T10:00:00.000Z'),
  (2, '22222222-2222-4222-8222-222222222222', 7, 'emulator', 'completed', '2026-11-02T10:00:00.000Z');
INSERT INTO models(id, name, version, params_json, created_at) VALUES (1, 'mill-1', 1, '{}', '2026-11-01T11:00:00.000Z');
INSERT INTO results(id, session_id, kind, payload_json, model_id, created_at) VALUES
  (1, 1, 'ssm', '{"test":1}', NULL, '2026-11-01T10:01:00.000Z'),
  (2, 2, 'identification', '{}', 1, '2026-11-02T10:01:00.000Z');
)sql");
        db.exec("COMMIT");
    }
    Store store(path);
    EXPECT_EQ(store.db().query_int("PRAGMA user_version"), Store::kSchemaVersion);
    EXPECT_EQ(store.integrity_check(), "ok");
    EXPECT_EQ(store.db().query_int("SELECT count(*) FROM pragma_foreign_key_check"), 0);
    EXPECT_TRUE(is_v4_uuid(store.station_uuid())) << store.station_uuid();
    EXPECT_EQ(store.session(1).uuid, "11111111-1111-4111-8111-111111111111");
    EXPECT_EQ(store.session(1).machine.name, "mill-2");
    auto want = machine_from_json(g1);
    want.name = "mill-1";  // the machines table's name column names it
    EXPECT_EQ(machine_to_json(store.session(2).machine), machine_to_json(want));
    EXPECT_EQ(store.session(2).machine_asset, "");
    std::vector<std::string> uuids;
    for (const char* table : {"machines", "models", "results"}) {
        auto st = store.db().prepare(std::string("SELECT uuid FROM ") + table);
        while (st.step()) uuids.push_back(st.column_text(0));
    }
    ASSERT_EQ(uuids.size(), 5u);
    for (const auto& u : uuids) EXPECT_TRUE(is_v4_uuid(u)) << u;
    std::sort(uuids.begin(), uuids.end());
    EXPECT_EQ(std::unique(uuids.begin(), uuids.end()), uuids.end()) << "one uuid per row";
    const auto machines = store.machines();
    ASSERT_EQ(machines.size(), 2u);
    EXPECT_EQ(machines[0].asset_id, "");
    EXPECT_EQ(machines[0].session_count, 1);
    // The registry on a migrated file: a registered machine may share an old one's geometry, and a
    // session measured by geometry alone still lands on the old row.
    NewMachine n;
    n.asset_id = "M-0042";
    n.name = "mill-1";
    n.geometry = machine_from_json(g1);
    EXPECT_EQ(store.register_machine(n).session_count, 0);
    NewSession s;
    s.machine = machine_from_json(g1);
    s.source = SessionSource::emulator;
    const auto by_geometry = store.create_session(s);
    EXPECT_EQ(store.session(by_geometry).machine_asset, "");
    EXPECT_EQ(store.db().query_int("SELECT machine_id FROM sessions WHERE id = " + std::to_string(by_geometry)), 7);
    s.machine_asset = "M-0042";
    EXPECT_EQ(store.session(store.create_session(s)).machine_asset, "M-0042");
}

INSTANTIATE_TEST_SUITE_P(Migration, FromEveryVersion, ::testing::Range(1, Store::kSchemaVersion),
                         [](const auto& p) { return "V" + std::to_string(p.param); });

TEST(Migration, ProcedureStepsStayOutOfTheLifecycle) {
    TempDir dir;
    Store store(dir.file("new.db"));
    NewSession s;
    s.machine.type = analysis::MachineType::TTTRR;
    const auto id = store.create_session(s);
    store.start_session(id);
    store.add_procedure_step(id, {"Connecting", "CheckingInstrument", "Connected", "emulator", ""});
    store.finish_session(id);
    ASSERT_EQ(store.transitions(id).size(), 3u);  // created, running, completed
    ASSERT_EQ(store.procedure_steps(id).size(), 1u);
    EXPECT_THROW(store.add_procedure_step(id + 1, {"a", "b", "c", "", ""}), StorageError);  // no such session
}

}  // namespace
}  // namespace ballbar::storage
