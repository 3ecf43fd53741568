// SPDX-License-Identifier: MIT
// SampleWriter: batching by device time and count, contiguous numbering, exact storage of fields.
#include <gtest/gtest.h>

#include <thread>

#include "ballbar/storage/sample_writer.hpp"
#include "test_util.hpp"

namespace ballbar::storage {
namespace {

using test::TempDir;

std::int64_t running_session(Store& store) {
    NewSession s;
    s.machine = test::tttrr();
    const auto id = store.create_session(s);
    store.start_session(id);
    return id;
}

analysis::BarSample at_us_sample_writer(std::uint64_t t, std::int32_t nm = 0) {
    analysis::BarSample s;
    s.device_time_us = t;
    s.displacement_nm = nm;
    return s;
}

TEST(SampleWriter, CommitsWhenABatchSpans50msOfDeviceTime) {
    TempDir dir;
    Store store(dir.file("a.db"));
    const auto id = running_session(store);
    SampleWriter w(store, id, {50'000, 65'536, std::chrono::hours(1)});
    // 1 kHz: samples 0..49 span 49 ms and stay pending; sample 50 (at 50 ms) completes the batch.
    for (std::uint64_t i = 0; i < 50; ++i) w.append(at_us_sample_writer(i * 1000));
    EXPECT_EQ(w.pending(), 50u);
    EXPECT_EQ(store.sample_count(id), 0);
    w.append(at_us_sample_writer(50'000));
    EXPECT_EQ(w.pending(), 0u);
    EXPECT_EQ(store.sample_count(id), 51);
    EXPECT_EQ(w.committed(), 51u);
    EXPECT_EQ(SampleWriterOptions{}.max_batch_device_time_us, 50'000u) << "the default";
}

TEST(SampleWriter, ASlowTrickleIsCommittedAfter50msOfWallTime) {
    TempDir dir;
    Store store(dir.file("a.db"));
    const auto id = running_session(store);
    SampleWriter w(store, id);  // defaults: 50 ms of device time or 50 ms of waiting
    w.append(at_us_sample_writer(0));
    w.append(at_us_sample_writer(1000));
    EXPECT_EQ(store.sample_count(id), 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(60));  // the link stalls
    w.append(at_us_sample_writer(2000));
    EXPECT_EQ(store.sample_count(id), 3) << "the batch's first sample waited 60 ms: committed";
}

TEST(SampleWriter, CommitsByCountAndRestartedDeviceClock) {
    TempDir dir;
    Store store(dir.file("a.db"));
    const auto id = running_session(store);
    SampleWriter w(store, id, {100'000, 50});
    for (int i = 0; i < 49; ++i) w.append(at_us_sample_writer(5));
    EXPECT_EQ(store.sample_count(id), 0);
    w.append(at_us_sample_writer(5));
    EXPECT_EQ(store.sample_count(id), 50);
    w.append(at_us_sample_writer(1000));
    w.append(at_us_sample_writer(10));  // clock went backwards: commit
    EXPECT_EQ(store.sample_count(id), 52);
}

TEST(SampleWriter, StoresEveryFieldAndNumbersContiguously) {
    TempDir dir;
    Store store(dir.file("a.db"));
    const auto id = running_session(store);
    {
        SampleWriter w(store, id);
        for (std::uint64_t i = 0; i < 1000; ++i) {
            analysis::BarSample s;
            s.seq = 5000 + i;  // the source's numbering is not the stored one
            s.device_time_us = 1'000'000'000'000ull + i * 500;
            s.displacement_nm = static_cast<std::int32_t>(i * 1234567 % 2000001) - 1000000;
            s.flags = static_cast<std::uint16_t>(i % 8);
            s.bar_temp_C = 20.0f + static_cast<float>(i) * 0.001f;
            EXPECT_EQ(w.append(s), i);
        }
    }  // the destructor flushes
    const auto back = store.samples(id);
    ASSERT_EQ(back.size(), 1000u);
    for (std::uint64_t i = 0; i < 1000; ++i) {
        EXPECT_EQ(back[i].seq, i);
        EXPECT_EQ(back[i].device_time_us, 1'000'000'000'000ull + i * 500);
        EXPECT_EQ(back[i].displacement_nm, static_cast<std::int32_t>(i * 1234567 % 2000001) - 1000000);
        EXPECT_EQ(back[i].flags, i % 8);
        EXPECT_NEAR(back[i].bar_temp_C, 20.0f + static_cast<float>(i) * 0.001f, 0.0006);
    }
    EXPECT_EQ(store.samples(id, 990, 5).front().seq, 990u);
    EXPECT_EQ(store.samples(id, 990, 5).size(), 5u);
    EXPECT_EQ(store.next_seq(id), 1000u);
}

/// Issue 25: the gap flag was dropped before storage and a session's gaps were never stored. A jump in
/// the source's numbering (a source leaves a hole where samples were lost) or the driver's flag is a
/// gap: recorded with where (the stored seq after it), how long (instrument time) and why, and the
/// stored sample after it keeps kSampleAfterGap. A writer that starts (a resume) or a clock that
/// restarts is no jump; a reconnect's gap has no duration.
TEST(SampleWriter, RecordsEveryGapWithWhereHowLongAndWhy) {
    TempDir dir;
    Store store(dir.file("g.db"));
    const auto id = running_session(store);
    auto sample = [](std::uint64_t seq, std::uint64_t t_us, std::uint16_t flags = 0) {
        analysis::BarSample s;
        s.seq = seq;
        s.device_time_us = t_us;
        s.flags = flags;
        return s;
    };
    {
        SampleWriter w(store, id);
        w.append(sample(0, 1000));
        w.append(sample(1, 2000));
        w.append(sample(3, 5000));  // a hole in the numbering: 3 ms
        w.append(sample(4, 6000));
        w.append(sample(5, 9000, analysis::kSampleAfterGap));  // the driver's flag
        w.append(sample(6, 100, analysis::kSampleAfterGap));   // a reconnect: the clock restarted
        w.append(sample(7, 200));
    }
    {
        SampleWriter again(store, id);  // a resume: its numbering starts again
        again.append(sample(0, 50));
        again.append(sample(1, 60));
    }
    const auto gaps = store.sample_gaps(id);
    ASSERT_EQ(gaps.size(), 3u);
    EXPECT_EQ(gaps[0].before_seq, 2u);
    ASSERT_TRUE(gaps[0].duration_s);
    EXPECT_NEAR(*gaps[0].duration_s, 0.003, 1e-12);
    EXPECT_EQ(gaps[0].cause, "lost frames");
    EXPECT_EQ(gaps[1].before_seq, 4u);
    EXPECT_NEAR(gaps[1].duration_s.value_or(0), 0.003, 1e-12);
    EXPECT_EQ(gaps[2].before_seq, 5u);
    EXPECT_FALSE(gaps[2].duration_s);
    EXPECT_EQ(gaps[2].cause, "reconnect");
    const auto back = store.samples(id);
    ASSERT_EQ(back.size(), 9u);
    for (std::size_t i = 0; i < back.size(); ++i) {
        const bool after_gap = i == 2 || i == 4 || i == 5;
        EXPECT_EQ((back[i].flags & analysis::kSampleAfterGap) != 0, after_gap) << "sample " << i;
    }
}

TEST(SampleWriter, RefusesASessionThatIsNotRunning) {
    TempDir dir;
    Store store(dir.file("a.db"));
    NewSession s;
    s.machine = test::tttrr();
    const auto id = store.create_session(s);
    EXPECT_THROW(SampleWriter(store, id), StorageError);
}

}  // namespace
}  // namespace ballbar::storage
