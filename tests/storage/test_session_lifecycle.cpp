// SPDX-License-Identifier: MIT
// Unfinished sessions: failed ones resume with their reason; a session whose writer is gone is
// `interrupted` for every reader (even one that does not write); sample segments and the monotonic
// session clock across a device-clock restart, a resume, and a v2 file without segments.
#include <gtest/gtest.h>

#include <chrono>

#include "ballbar/storage/machine_json.hpp"
#include "ballbar/storage/sample_writer.hpp"
#include "ballbar/storage/session_clock.hpp"
#include "ballbar/storage/store.hpp"
#include "schema.hpp"
#include "test_util.hpp"

namespace ballbar::storage {
namespace {

using test::TempDir;
using namespace std::chrono;

NewSession tttrr_session() {
    NewSession s;
    s.machine = test::tttrr();
    s.source = SessionSource::emulator;
    return s;
}

/// A Store clock the test moves: 2026-11-01T10:00:00Z + `offset`.
struct TestClock {
    milliseconds offset{0};
    StoreOptions options(bool recover = true) {
        StoreOptions o;
        o.clock = [this] { return system_clock::time_point(seconds(1793527200)) + offset; };
        o.recover = recover;
        return o;
    }
};

analysis::BarSample at_us(std::uint64_t t, std::int32_t nm = 0) {
    analysis::BarSample s;
    s.device_time_us = t;
    s.displacement_nm = nm;
    s.bar_temp_C = 20.0f;
    return s;
}

TEST(Lifecycle, FailedSessionResumesWithItsReason) {
    TempDir dir;
    Store store(dir.file("a.db"));
    const auto id = store.create_session(tttrr_session());
    store.start_session(id);
    {
        SampleWriter w(store, id);
        for (int i = 0; i < 5; ++i) w.append(at_us(1000u * static_cast<unsigned>(i)));
    }
    store.fail_session(id, "fail: no samples from the instrument for 30 s");
    auto info = store.session(id);
    EXPECT_EQ(info.state, SessionState::failed);
    EXPECT_TRUE(info.resumable());
    EXPECT_EQ(info.reason, "fail: no samples from the instrument for 30 s");
    EXPECT_TRUE(info.ended_at);
    EXPECT_EQ(store.resume_session(id), 5u);
    info = store.session(id);
    EXPECT_EQ(info.state, SessionState::running);
    EXPECT_FALSE(info.ended_at) << "a resumed session has not ended";
    EXPECT_EQ(store.transitions(id).back().event, "resume after fail");
    SampleWriter w(store, id);
    EXPECT_EQ(w.append(at_us(99'000)), 5u);
}

TEST(Lifecycle, CompletedAndAbortedSessionsAreNotResumable) {
    TempDir dir;
    Store store(dir.file("a.db"));
    for (const bool complete : {true, false}) {
        const auto id = store.create_session(tttrr_session());
        store.start_session(id);
        complete ? store.finish_session(id) : store.abort_session(id, "abort: the operator stopped");
        EXPECT_FALSE(store.session(id).resumable());
        try {
            store.resume_session(id);
            FAIL() << "resumed a " << to_string(store.session(id).state) << " session";
        } catch (const StorageError& e) {
            EXPECT_EQ(e.kind(), StorageError::Kind::invalid);
            EXPECT_NE(std::string(e.what()).find("only an unfinished"), std::string::npos) << e.what();
        }
    }
}

TEST(Lifecycle, EveryReaderSeesASessionWhoseWriterIsGoneAsInterrupted) {
    TempDir dir;
    const auto path = dir.file("a.db");
    std::int64_t id = 0;
    StoreOptions no_recovery;
    no_recovery.recover = false;
    StoreOptions read_only;
    read_only.read_only = true;
    {
        Store writer(path);
        id = writer.create_session(tttrr_session());
        writer.start_session(id);
        // While its writer lives, readers see it running.
        Store lister(path, no_recovery);
        EXPECT_EQ(lister.session(id).state, SessionState::running);
        EXPECT_FALSE(lister.session(id).writer_gone);
        Store ro(path, read_only);
        EXPECT_EQ(ro.sessions().at(0).state, SessionState::running);
        EXPECT_TRUE(writer.writer_alive(id));
        EXPECT_TRUE(ro.writer_alive(id));
    }  // the writer is gone without finishing (as after kill -9: the kernel drops its lock)
    {
        Store lister(path, no_recovery);
        const auto info = lister.session(id);
        EXPECT_EQ(info.state, SessionState::interrupted);
        EXPECT_TRUE(info.writer_gone);
        EXPECT_TRUE(info.resumable());
        EXPECT_NE(info.reason.find("writer is gone"), std::string::npos) << info.reason;
        Store ro(path, read_only);
        EXPECT_EQ(ro.sessions().at(0).state, SessionState::interrupted);
        EXPECT_EQ(lister.db().query_text("SELECT state FROM sessions"), "running") << "listing wrote nothing";
        // A Store that does not recover on open can still resume it: interrupted is recorded first.
        lister.resume_session(id);
        const auto tr = lister.transitions(id);
        ASSERT_GE(tr.size(), 2u);
        EXPECT_EQ(tr[tr.size() - 2].to, SessionState::interrupted);
        EXPECT_EQ(tr.back().event, "resume");
        Store other(path, no_recovery);
        EXPECT_EQ(other.session(id).state, SessionState::running) << "now owned by `lister`";
        EXPECT_THROW(other.resume_session(id), StorageError) << "a live writer's session is not taken";
    }
}

TEST(Lifecycle, SetInstrumentRecordsTheIdentity) {
    TempDir dir;
    Store store(dir.file("a.db"));
    const auto id = store.create_session(tttrr_session());
    EXPECT_FALSE(store.session(id).instrument);
    Instrument in;
    in.model = "BB-1E";
    in.serial = "EMU00001";
    in.firmware = "1.0.0";
    in.calibrated_length_mm = 150.0;
    in.calibration_date = "2026-01-15";
    store.set_instrument(id, in);
    const auto got = store.session(id).instrument;
    ASSERT_TRUE(got);
    EXPECT_EQ(got->model, "BB-1E");
    EXPECT_EQ(got->serial, "EMU00001");
    EXPECT_EQ(got->firmware, "1.0.0");
    EXPECT_EQ(got->calibrated_length_mm, 150.0);
    EXPECT_EQ(got->calibration_date, "2026-01-15");
    EXPECT_THROW(store.set_instrument(id + 7, in), StorageError);
}

TEST(SessionClock, RestartedDeviceClockAndResumeGiveOneMonotonicTime) {
    TempDir dir;
    const auto path = dir.file("a.db");
    TestClock wall;
    std::int64_t id = 0;
    {
        Store store(path, wall.options());
        id = store.create_session(tttrr_session());  // started_at 10:00:00.000
        store.start_session(id);
        SampleWriter w(store, id);
        wall.offset = 500ms;
        for (std::uint64_t i = 0; i < 1000; ++i) w.append(at_us(7'000'000 + i * 1000));  // 1 s of samples
        wall.offset = 10s;  // replug: the instrument restarted, its clock from ~0
        for (std::uint64_t i = 0; i < 500; ++i) w.append(at_us(2'000 + i * 1000));
        wall.offset = 12s;  // a reconnect the caller knows of, same device clock going on
        w.begin_segment();
        for (std::uint64_t i = 0; i < 100; ++i) w.append(at_us(2'000'000 + i * 1000));
    }  // killed, say
    wall.offset = 60s;
    Store store(path, wall.options());
    store.resume_session(id);
    {
        SampleWriter w(store, id);
        wall.offset = 61s;  // the new process's first sample; the device clock went on
        for (std::uint64_t i = 0; i < 100; ++i) w.append(at_us(50'000'000 + i * 1000));
    }
    const auto segs = store.sample_segments(id);
    ASSERT_EQ(segs.size(), 4u);
    EXPECT_EQ(segs[0].first_seq, 0u);
    EXPECT_EQ(segs[1].first_seq, 1000u);
    EXPECT_EQ(segs[1].device_time_us, 2'000u);
    EXPECT_EQ(segs[2].first_seq, 1500u);
    EXPECT_EQ(segs[3].first_seq, 1600u);
    EXPECT_EQ(segs[3].started_at, "2026-11-01T10:01:01.000Z");

    const SessionClock clock(store, id);
    EXPECT_EQ(clock.segments(), 4u);
    // The first sample (wall 0.5 s) is at 0; the others as long after it as their writer's clock says.
    EXPECT_NEAR(clock.first_s(), 0.0, 1e-9);
    EXPECT_NEAR(clock.seconds(999, 7'999'000), 0.999, 1e-9);
    EXPECT_NEAR(clock.seconds(1000, 2'000), 9.5, 1e-9);
    EXPECT_NEAR(clock.seconds(1499, 501'000), 9.999, 1e-9);
    EXPECT_NEAR(clock.seconds(1500, 2'000'000), 11.5, 1e-9);
    EXPECT_NEAR(clock.seconds(1600, 50'000'000), 60.5, 1e-9);
    EXPECT_NEAR(clock.last_s(), 60.599, 1e-9);
    EXPECT_NEAR(clock.sampled_s(), 0.999 + 0.499 + 0.099 + 0.099, 1e-9);
    double prev = -1;
    for (const auto& s : store.samples(id)) {
        const double t = clock.seconds(s.seq, s.device_time_us);
        ASSERT_GT(t, prev) << "seq " << s.seq;
        prev = t;
    }
}

TEST(SessionClock, SegmentsNeverOverlapWhenTheWallClockLags) {
    TempDir dir;
    TestClock wall;
    Store store(dir.file("a.db"), wall.options());
    const auto id = store.create_session(tttrr_session());
    store.start_session(id);
    SampleWriter w(store, id);
    for (std::uint64_t i = 0; i < 3000; ++i) w.append(at_us(1'000 + i * 1000));  // 3 s, wall still at 0
    for (std::uint64_t i = 0; i < 10; ++i) w.append(at_us(500 + i * 1000));      // device restarted
    w.flush();
    const SessionClock clock(store, id);
    EXPECT_NEAR(clock.seconds(2999, 3'000'000), 2.999, 1e-9);
    EXPECT_NEAR(clock.seconds(3000, 500), 3.0, 1e-9) << "one period after the previous segment's last sample";
}

/// A session as schema v2 stored it: samples only (no segments), the device clock restarting twice.
TEST(SessionClock, V2FileWithoutSegmentsMigratesAndGetsDerivedSegments) {
    TempDir dir;
    const auto path = dir.file("v2.db");
    {
        Database db(path);
        db.exec("BEGIN");
        db.exec(detail::kMigrations[0]);
        db.exec(detail::kMigrations[1]);
        db.exec("PRAGMA user_version = 2");
        db.exec("PRAGMA application_id = " + std::to_string(Store::kApplicationId));
        db.prepare("INSERT INTO machines(id, name, type, geometry_json) VALUES (1, 'm', 'TTTRR', ?)")
            .bind(1, machine_to_json(test::tttrr()))
            .run();
        db.exec(R"sql(
INSERT INTO sessions(id, uuid, machine_id, source, state, started_at)
  VALUES (1, '22222222-2222-4222-8222-222222222222', 1, 'emulator', 'interrupted', '2026-11-01T10:00:00.000Z');
INSERT INTO session_transitions(session_id, from_state, to_state, event, at, scope) VALUES
  (1, NULL, 'created', 'create', '2026-11-01T10:00:00.000Z', 'session'),
  (1, 'created', 'running', 'start', '2026-11-01T10:00:00.001Z', 'session'),
  (1, 'running', 'interrupted', 'interrupted: found unfinished on open', '2026-11-01T10:05:00.000Z', 'session');
)sql");
        auto ins = db.prepare(
            "INSERT INTO samples(session_id, seq, device_time_us, displacement_nm, flags, bar_temp_mC) "
            "VALUES (1, ?, ?, 0, 0, 20000)");
        std::int64_t seq = 0;
        for (const std::int64_t start : {4'000'000, 1'000, 3'000}) {  // 2 ms period in the last run
            for (std::int64_t i = 0; i < 200; ++i, ++seq) {
                ins.bind(1, seq).bind(2, start + i * (start == 3'000 ? 2000 : 1000)).run();
                ins.reset();
            }
        }
        db.exec("COMMIT");
    }
    Store store(path);
    EXPECT_EQ(store.db().query_int("PRAGMA user_version"), Store::kSchemaVersion);
    EXPECT_EQ(store.integrity_check(), "ok");
    EXPECT_TRUE(store.sample_segments(1).empty());
    EXPECT_EQ(store.sample_count(1), 600);
    const SessionClock clock(store, 1);
    EXPECT_EQ(clock.segments(), 3u);
    EXPECT_NEAR(clock.seconds(0, 4'000'000), 0.0, 1e-12);
    EXPECT_NEAR(clock.seconds(200, 1'000), 0.199 + 0.001, 1e-9);
    EXPECT_NEAR(clock.seconds(400, 3'000), 0.399 + 0.001, 1e-9);
    EXPECT_NEAR(clock.last_s(), 0.400 + 199 * 0.002, 1e-9);
    // The migrated file takes segments from now on.
    store.resume_session(1);
    {
        SampleWriter w(store, 1);
        w.append(at_us(10'000'000));
    }
    ASSERT_EQ(store.sample_segments(1).size(), 1u);
    EXPECT_EQ(store.sample_segments(1)[0].first_seq, 600u);
}

}  // namespace
}  // namespace ballbar::storage
