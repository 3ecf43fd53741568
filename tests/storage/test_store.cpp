// SPDX-License-Identifier: MIT
// Store: schema creation, session lifecycle and audit trail, points, results, models, lookup.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <functional>

#include "ballbar/analysis/kinematics.hpp"
#include "ballbar/storage/readings.hpp"
#include "ballbar/storage/sample_writer.hpp"
#include "ballbar/storage/store.hpp"
#include "test_util.hpp"

namespace ballbar::storage {
namespace {

using test::TempDir;

StoreOptions fixed_clock() {
    StoreOptions o;
    o.clock = [] { return std::chrono::system_clock::time_point(std::chrono::seconds(1'800'000'000)); };
    return o;
}

NewSession new_session() {
    NewSession s;
    s.machine = test::tttrr();
    s.instrument = Instrument{"BB-100", "0042", "1.2", 100.0, "2026-01-02", ""};
    s.source = SessionSource::emulator;
    s.operator_name = "ada";
    s.procedure = "ssm";
    return s;
}

TEST(Store, CreatesSchemaInWalModeWithVersion) {
    TempDir dir;
    Store store(dir.file("a.db"));
    EXPECT_EQ(store.db().query_int("PRAGMA user_version"), Store::kSchemaVersion);
    EXPECT_EQ(store.db().query_int("PRAGMA application_id"), Store::kApplicationId);
    EXPECT_EQ(store.db().query_text("PRAGMA journal_mode"), "wal");
    EXPECT_EQ(store.integrity_check(), "ok");
}

TEST(Store, SessionLifecycleRecordsEveryTransition) {
    TempDir dir;
    Store store(dir.file("a.db"), fixed_clock());
    const auto id = store.create_session(new_session());
    store.start_session(id);
    store.finish_session(id);
    const auto info = store.session(id);
    EXPECT_EQ(info.state, SessionState::completed);
    EXPECT_EQ(info.operator_name, "ada");
    EXPECT_EQ(info.source, SessionSource::emulator);
    EXPECT_EQ(info.machine.type, analysis::MachineType::TTTRR);
    EXPECT_EQ(info.machine.c_offset_mm.z(), -100);
    ASSERT_TRUE(info.instrument);
    EXPECT_EQ(info.instrument->serial, "0042");
    EXPECT_EQ(info.started_at, "2027-01-15T08:00:00.000Z");
    ASSERT_TRUE(info.ended_at);
    EXPECT_EQ(info.uuid.size(), 36u);
    EXPECT_EQ(info.uuid[14], '4');
    const auto tr = store.transitions(id);
    ASSERT_EQ(tr.size(), 3u);
    EXPECT_FALSE(tr[0].from);
    EXPECT_EQ(tr[0].to, SessionState::created);
    EXPECT_EQ(tr[1].from, SessionState::created);
    EXPECT_EQ(tr[1].to, SessionState::running);
    EXPECT_EQ(tr[2].to, SessionState::completed);
    EXPECT_EQ(tr[2].event, "finish");
}

TEST(Store, IllegalTransitionsAreRefusedAndNotRecorded) {
    TempDir dir;
    Store store(dir.file("a.db"));
    const auto id = store.create_session(new_session());
    store.start_session(id);
    store.finish_session(id);
    for (const auto to : {SessionState::created, SessionState::running, SessionState::aborted, SessionState::failed,
                          SessionState::interrupted, SessionState::completed}) {
        try {
            store.transition(id, to, "x");
            FAIL() << "completed → " << to_string(to) << " accepted";
        } catch (const StorageError& e) {
            EXPECT_EQ(e.kind(), StorageError::Kind::invalid);
            EXPECT_NE(std::string(e.what()).find("cannot go from completed"), std::string::npos);
        }
    }
    EXPECT_EQ(store.transitions(id).size(), 3u);
    EXPECT_THROW(store.resume_session(id), StorageError);
    EXPECT_FALSE(transition_allowed(SessionState::created, SessionState::failed));
    EXPECT_TRUE(transition_allowed(SessionState::interrupted, SessionState::running));
}

TEST(Store, UnfinishedSessionIsInterruptedOnReopenAndResumable) {
    TempDir dir;
    const auto path = dir.file("a.db");
    std::int64_t id = 0;
    {
        Store store(path);
        id = store.create_session(new_session());
        store.start_session(id);
        SampleWriter w(store, id);
        for (int i = 0; i < 10; ++i) w.append({0, static_cast<std::uint64_t>(i) * 1000, i, 0, 20.5f});
    }  // the Store closes without finishing: its owner is gone
    Store store(path);
    ASSERT_EQ(store.recovered_sessions(), std::vector<std::int64_t>{id});
    EXPECT_EQ(store.session(id).state, SessionState::interrupted);
    EXPECT_EQ(store.transitions(id).back().from, SessionState::running);
    EXPECT_EQ(store.resume_session(id), 10u);
    SampleWriter w(store, id);
    EXPECT_EQ(w.append({}), 10u);
    w.flush();
    EXPECT_EQ(store.sample_count(id), 11);
    EXPECT_EQ(store.transitions(id).back().event, "resume");
}

/// Runs `body` in a child process as a user who may not write what root may (nobody, 65534, when
/// the tests run as root); its return value is the exit code.
int as_another_user(const std::function<int()>& body) {
    const pid_t pid = ::fork();
    if (pid < 0) return -1;
    if (pid == 0) {
        if (::getuid() == 0 && (::setgid(65534) != 0 || ::setuid(65534) != 0)) ::_exit(100);
        int code = 101;
        try {
            code = body();
        } catch (...) {
        }
        ::_exit(code);
    }
    int st = 0;
    ::waitpid(pid, &st, 0);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/// Issue 24: `sessions` and `report` in a read-only directory failed with "attempt to write a readonly
/// database". A reader reads a WAL database it may not write, in a directory it may not write (no
/// -shm can be made there); a writer is told plainly that it may not write, and nothing is changed.
TEST(Store, AReaderReadsAFileAndDirectoryItMayNotWriteAndAWriterIsToldWhy) {
    TempDir dir;
    const std::string path = dir.file("archive.db");
    {
        Store store(path, fixed_clock());
        const auto id = store.create_session(new_session());
        store.start_session(id);
        store.finish_session(id);
    }
    ASSERT_FALSE(std::filesystem::exists(path + "-wal"));
    const std::string before = test::slurp(path);
    ::chmod(path.c_str(), 0444);
    ::chmod((path + ".lock").c_str(), 0444);
    ::chmod(dir.path().c_str(), 0555);
    const int reader = as_another_user([&] {
        StoreOptions o;
        o.recover = false;  // as `sessions`, `export` and `circle analyze` open
        Store store(path, o);
        const auto list = store.sessions();
        return list.size() == 1 && list[0].state == SessionState::completed ? 0 : 2;
    });
    const int report = as_another_user([&] {
        StoreOptions o;
        o.read_only = true;  // as `report` opens
        o.recover = false;
        Store store(path, o);
        return store.sessions().size() == 1 ? 0 : 2;
    });
    const int writer = as_another_user([&] {
        try {
            Store store(path);
            return 3;
        } catch (const StorageError& e) {
            return std::string(e.what()).find("read-only to this user") != std::string::npos ? 0 : 4;
        }
    });
    ::chmod(dir.path().c_str(), 0755);
    ::chmod(path.c_str(), 0644);
    EXPECT_EQ(reader, 0);
    EXPECT_EQ(report, 0);
    EXPECT_EQ(writer, 0);
    EXPECT_EQ(test::slurp(path), before) << "a reader changed the file";
    EXPECT_FALSE(std::filesystem::exists(path + "-wal"));
    EXPECT_FALSE(std::filesystem::exists(path + "-shm"));
}

TEST(Store, LiveSessionOfAnotherStoreIsNotInterrupted) {
    TempDir dir;
    const auto path = dir.file("a.db");
    Store writer(path);
    const auto id = writer.create_session(new_session());
    writer.start_session(id);
    Store reader(path);  // opens while the writer is alive and owns the session
    EXPECT_TRUE(reader.recovered_sessions().empty());
    EXPECT_EQ(reader.session(id).state, SessionState::running);
    EXPECT_THROW(reader.transition(id, SessionState::running, "steal"), StorageError);
    writer.finish_session(id);
    EXPECT_EQ(reader.session(id).state, SessionState::completed);
}

TEST(Store, PointsRoundTripExactly) {
    TempDir dir;
    Store store(dir.file("a.db"));
    const auto id = store.create_session(new_session());
    PointRecord p;
    p.reading.pose = {32.375, -14.312, -120.042, 0.1, 0, -0.7};
    p.reading.socket_mm = {-49.275, -14.312, -77.777};
    p.reading.measured_mm = 100.0021;
    p.reading.time_s = 12.0;
    p.reading.bar_temp_C = 20.31;
    p.reading.location = 2;
    p.reading.point = 3;
    p.reading.step = 1;
    p.reading.n = 250;
    p.reading.std_mm = 0.00012;
    p.nominal_mm = analysis::nominal_length(test::tttrr(), p.reading.pose, p.reading.socket_mm);
    p.first_seq = 100;
    p.last_seq = 349;
    EXPECT_EQ(store.add_point(id, p), 0);
    EXPECT_EQ(store.add_point(id, p), 1);
    const auto points = store.points(id);
    ASSERT_EQ(points.size(), 2u);
    const auto& q = points[1];
    EXPECT_EQ(q.index, 1);
    EXPECT_EQ(q.reading.pose.C_rad, -0.7);
    EXPECT_EQ(q.reading.socket_mm, p.reading.socket_mm);
    EXPECT_EQ(q.reading.measured_mm, 100.0021);
    EXPECT_EQ(q.reading.bar_temp_C, 20.31);
    EXPECT_FALSE(q.reading.air_temp_C);
    EXPECT_EQ(q.reading.std_mm, 0.00012);
    EXPECT_EQ(q.first_seq, 100u);
    EXPECT_EQ(q.last_seq, 349u);
    EXPECT_EQ(q.nominal_mm, p.nominal_mm);
    const auto set = load_readings(store, id);
    EXPECT_EQ(set.machine.type, analysis::MachineType::TTTRR);
    ASSERT_EQ(set.readings.size(), 2u);
    EXPECT_EQ(set.readings[0].n, 250);
    EXPECT_THROW(store.add_point(999, p), StorageError);
}

TEST(Store, ResultsAndModelHistory) {
    TempDir dir;
    Store store(dir.file("a.db"));
    const auto s1 = store.create_session(new_session());
    const auto s2 = store.create_session(new_session());
    const auto m1 = store.save_model("DL-5X", R"({"EXA":1e-6})", {s1});
    const auto m2 = store.save_model("DL-5X", R"({"EXA":2e-6})", {s1, s2}, m1.id, "refined");
    EXPECT_EQ(m1.version, 1);
    EXPECT_EQ(m2.version, 2);
    EXPECT_EQ(m2.parent_id, m1.id);
    EXPECT_EQ(m2.session_ids, (std::vector<std::int64_t>{s1, s2}));
    EXPECT_EQ(store.model_history("DL-5X").size(), 2u);
    EXPECT_EQ(store.latest_model("DL-5X")->params_json, R"({"EXA":2e-6})");
    EXPECT_FALSE(store.latest_model("other"));
    const auto r = store.add_result(s2, "identification", R"({"rms_um":1.5})", m2.id, "ballbar 0.1.0");
    const auto results = store.results(s2);
    ASSERT_EQ(results.size(), 1u);
    EXPECT_EQ(results[0].id, r);
    EXPECT_EQ(results[0].kind, "identification");
    EXPECT_EQ(results[0].model_id, m2.id);
    EXPECT_TRUE(store.results(s1).empty());
}

TEST(Store, FindsSessionsByIdOrUuidPrefix) {
    TempDir dir;
    Store store(dir.file("a.db"));
    const auto a = store.create_session(new_session());
    const auto b = store.create_session(new_session());
    const auto uuid_b = store.session(b).uuid;
    EXPECT_EQ(store.find_session(std::to_string(a)), a);
    EXPECT_EQ(store.find_session(uuid_b.substr(0, 8)), b);
    EXPECT_EQ(store.find_session(uuid_b), b);
    EXPECT_THROW(store.find_session("zz"), StorageError);
    EXPECT_THROW(store.find_session("999"), StorageError);
    EXPECT_EQ(store.sessions().size(), 2u);
    // A short number is an id only, whatever the uuids start with (CliStorage.SessionsListsAndShows
    // failed once when a random uuid began with the 99 it asks for); 8 digits and more may be a prefix.
    store.db().exec("UPDATE sessions SET uuid = '99123456' || substr(uuid, 9) WHERE id = " + std::to_string(b));
    EXPECT_THROW(store.find_session("99"), StorageError);
    EXPECT_THROW(store.find_session("9912345"), StorageError);
    EXPECT_EQ(store.find_session("99123456"), b);
    EXPECT_EQ(store.find_session("99123456-"), b);
}

TEST(Store, ReadOnlyOpenOfMissingFileFails) {
    TempDir dir;
    StoreOptions o;
    o.read_only = true;
    EXPECT_THROW(Store(dir.file("none.db"), o), StorageError);
    EXPECT_FALSE(std::filesystem::exists(dir.file("none.db")));
}

}  // namespace
}  // namespace ballbar::storage
