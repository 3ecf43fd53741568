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

analysis::BarSample at_us(std::uint64_t t, std::int32_t nm = 0) {
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
    for (std::uint64_t i = 0; i < 50; ++i) w.append(at_us(i * 1000));
    EXPECT_EQ(w.pending(), 50u);
    EXPECT_EQ(store.sample_count(id), 0);
    w.append(at_us(50'000));
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
    w.append(at_us(0));
    w.append(at_us(1000));
    EXPECT_EQ(store.sample_count(id), 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(60));  // the link stalls
    w.append(at_us(2000));
    EXPECT_EQ(store.sample_count(id), 3) << "the batch's first sample waited 60 ms: committed";
}

TEST(SampleWriter, CommitsByCountAndRestartedDeviceClock) {
    TempDir dir;
    Store store(dir.file("a.db"));
    const auto id = running_session(store);
    SampleWriter w(store, id, {100'000, 50});
    for (int i = 0; i < 49; ++i) w.append(at_us(5));
    EXPECT_EQ(store.sample_count(id), 0);
    w.append(at_us(5));
    EXPECT_EQ(store.sample_count(id), 50);
    w.append(at_us(1000));
    w.append(at_us(10));  // clock went backwards: commit
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
            s.seq = 5000 + i * 3;  // the device's numbering is not the stored one
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
