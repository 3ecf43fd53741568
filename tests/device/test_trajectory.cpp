// SPDX-License-Identifier: MIT
// A machine that follows a controller (device/trajectory.hpp): halsampler's lines as LinuxCNC writes
// them, their playback behind the newest cycle, and the emulated machine standing where they say.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <memory>
#include <numbers>
#include <string>
#include <thread>

#include "ballbar/device/trajectory.hpp"

namespace ballbar::device {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

TEST(TrajectorySample, ReadsHalsamplersLineOfAnXyzacMachine) {
    // halsampler -t: the sample number, then the pins with six decimals (docs/linuxcnc.md).
    const auto s = parse_xyzac_sample("1234 -49.275000 14.312000 -77.777000 30.000000 -120.500000 7 0");
    ASSERT_TRUE(s);
    EXPECT_EQ(s->cycle, 1234u);
    EXPECT_DOUBLE_EQ(s->pose.X_mm, -49.275);
    EXPECT_DOUBLE_EQ(s->pose.Y_mm, 14.312);
    EXPECT_DOUBLE_EQ(s->pose.Z_mm, -77.777);
    EXPECT_DOUBLE_EQ(s->pose.A_rad, 30.0 * kDeg);
    EXPECT_DOUBLE_EQ(s->pose.B_rad, 0.0);
    EXPECT_DOUBLE_EQ(s->pose.C_rad, -120.5 * kDeg);
}

TEST(TrajectorySample, RefusesWhatIsNotOne) {
    for (const char* line : {"", "overrun", "12 1 2 3 4", "x 1 2 3 4 5", "12 1 2 nan 4 5", "12 1 2 3e999 4 5",
                             "-3 1 2 3 4 5", "12 1 2 3 4 5x"})
        EXPECT_FALSE(parse_xyzac_sample(line)) << "'" << line << "'";
}

JointSample at(std::uint64_t cycle, double x) {
    JointSample s;
    s.cycle = cycle;
    s.pose.X_mm = x;
    return s;
}

TEST(TrajectoryFeed, PlaysEachCycleTheDelayBehindTheNewestItHadAtFirst) {
    TrajectoryFeed feed(0.001, 0.010);  // 1 ms cycles, 10 ms behind
    EXPECT_FALSE(feed.pose_at(5.0));    // nothing yet: the machine stands where it stood
    for (std::uint64_t c = 100; c <= 120; ++c) feed.push(at(c, static_cast<double>(c)));
    // Emulator time 5 s plays cycle 110 (120 − 10 ms); every millisecond later, the next cycle (the
    // times asked are between two cycles' times, clear of rounding).
    EXPECT_DOUBLE_EQ(feed.pose_at(5.0)->X_mm, 110.0);
    EXPECT_DOUBLE_EQ(feed.pose_at(5.0034)->X_mm, 113.0);
    EXPECT_EQ(feed.starved(), 0u);
    // Past the newest cycle's time the machine stands at it, and the feed says it ran dry (once for
    // the whole wait).
    EXPECT_DOUBLE_EQ(feed.pose_at(5.0105)->X_mm, 120.0);
    EXPECT_DOUBLE_EQ(feed.pose_at(5.030)->X_mm, 120.0);
    EXPECT_DOUBLE_EQ(feed.pose_at(5.040)->X_mm, 120.0);
    EXPECT_EQ(feed.starved(), 1u);
    // A late burst: the playback goes on from its own clock, not from the burst.
    for (std::uint64_t c = 121; c <= 160; ++c) feed.push(at(c, static_cast<double>(c)));
    EXPECT_DOUBLE_EQ(feed.pose_at(5.0455)->X_mm, 155.0);
    // An old or repeated cycle is ignored.
    feed.push(at(150, -1.0));
    feed.push(at(160, -1.0));
    EXPECT_DOUBLE_EQ(feed.pose_at(5.0465)->X_mm, 156.0);
    EXPECT_EQ(feed.cycles(), 61u);
}

TEST(TrajectoryFeed, ReadsLinesFromAPipeAcrossReadsAndSkipsOthers) {
    int fds[2];
    ASSERT_EQ(::pipe(fds), 0);
    auto feed = std::make_shared<TrajectoryFeed>(0.001, 0.0);
    std::atomic<bool> stop{false};
    std::size_t rejected = 0;
    std::thread reader([&] { rejected = feed->read_lines(fds[0], stop); });
    const std::string text = "1 1 0 0 0 0\n2 2 0 0 0 0\noverrun\n3 3 0 0";
    ASSERT_EQ(::write(fds[1], text.data(), text.size()), static_cast<ssize_t>(text.size()));
    ASSERT_EQ(::write(fds[1], " 0 0\n", 5), 5);  // the rest of line 3 in another write
    ::close(fds[1]);                             // the writer's end: the reader returns
    reader.join();
    ::close(fds[0]);
    EXPECT_EQ(rejected, 1u);
    EXPECT_EQ(feed->cycles(), 3u);
}

TEST(TrajectoryFeed, TheMachineStandsWhereTheControllerSaysAndRemembersIt) {
    MachineSetup setup;
    setup.geometry.type = analysis::MachineType::TTTRR;
    setup.start = {1, 2, 3, 0, 0, 0};
    SimulatedMachine m(setup);
    m.keep_history();
    auto feed = std::make_shared<TrajectoryFeed>(0.001, 0.009);  // plays the first of 10 cycles first
    m.follow(feed);
    EXPECT_DOUBLE_EQ(m.pose_at(0.5).X_mm, 1.0);  // no cycle yet: where it stood
    for (std::uint64_t c = 0; c < 10; ++c) {
        JointSample s = at(c, 10.0 + static_cast<double>(c));
        s.pose.A_rad = 0.1;
        feed->push(s);
    }
    EXPECT_DOUBLE_EQ(m.pose_at(1.0).X_mm, 10.0);
    EXPECT_DOUBLE_EQ(m.pose_at(1.0055).X_mm, 15.0);
    EXPECT_DOUBLE_EQ(m.pose_at(1.0055).A_rad, 0.1);
    // What a checker asks afterwards: the pose at each past time.
    EXPECT_DOUBLE_EQ(m.truth_at(0.7)->pose.X_mm, 1.0);
    EXPECT_DOUBLE_EQ(m.truth_at(1.0)->pose.X_mm, 10.0);
    EXPECT_DOUBLE_EQ(m.truth_at(1.005)->pose.X_mm, 10.0);  // asked at 1.0 and 1.0055 only: a step at each
    EXPECT_DOUBLE_EQ(m.truth_at(1.0055)->pose.X_mm, 15.0);
    // Its own motion queue is no longer used.
    m.move_to({0, 0, 0, 0, 0, 0}, 1000);
    EXPECT_DOUBLE_EQ(m.pose_at(2.0).X_mm, 19.0);
}

}  // namespace
}  // namespace ballbar::device
