// SPDX-License-Identifier: MIT
// Schema migrations on real old databases: a v1 file (made with v1's own schema text) opened by this
// version is migrated in place, loses nothing and keeps working.
#include <gtest/gtest.h>

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
