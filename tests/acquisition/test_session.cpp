// SPDX-License-Identifier: MIT
// The whole procedure against a simulated machine with injected errors (device::SimulatedMachine runs
// the plan's NC program; the bar reads it at 1 kHz with 0.1 µm noise). "True" values: the exact total
// position error (b − s)_actual − (b − s)_nominal of the machine's kinematics at the planned points, and
// the orientation errors the same (exact) orientation model gives for those exact errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "ballbar/acquisition/compute.hpp"
#include "ballbar/acquisition/session.hpp"
#include "sim_source.hpp"

namespace ballbar::acquisition {
namespace {

using analysis::MachineType;
using testing::RecordingSink;
using testing::SimOptions;
using testing::SimSource;

constexpr double kPositionTol_mm = 0.001;                               // 1 µm
constexpr double kAngleTol_rad = 2.0 / 3600.0 * analysis::kPi / 180.0;  // 2 arcsec

using testing::SimOperator;
using testing::SimOperatorOptions;
using testing::window_at_planned_pose;

device::MachineSetup setup_for(const Plan& plan, std::size_t from = 0) {
    device::MachineSetup s;
    s.geometry = plan.machine.geometry;
    s.errors = demo_errors(plan.machine.geometry.type);
    s.socket_mm = plan.points.front().socket_mm;
    s.start = plan.points[from].pose;
    return s;
}

void expect_matches_truth(const Plan& plan, const RecordingSink& sink) {
    const auto truth = true_values(plan, demo_errors(plan.machine.geometry.type));
    ASSERT_EQ(sink.tests.size(), truth.size());
    ASSERT_EQ(sink.locations.size(), 2 * truth.size());
    for (std::size_t t = 0; t < truth.size(); ++t) {
        const auto& e1 = sink.locations[2 * t].ssm.exact_mm;
        const auto& e2 = sink.locations[2 * t + 1].ssm.exact_mm;
        EXPECT_LT((e1 - truth[t].e1_mm).norm(), kPositionTol_mm)
            << "test " << t << " e1 " << e1.transpose() << " true " << truth[t].e1_mm.transpose();
        EXPECT_LT((e2 - truth[t].e2_mm).norm(), kPositionTol_mm) << "test " << t;
        EXPECT_GT(truth[t].e2_mm.norm(), 0.005) << "the injected errors must show";
        const auto& got = sink.tests[t].orientation;
        const auto& want = truth[t].result.orientation;
        ASSERT_TRUE(got.exact && want.exact) << got.singular;
        EXPECT_NEAR(got.exact->d_alpha_rad, want.exact->d_alpha_rad, kAngleTol_rad) << "test " << t;
        EXPECT_NEAR(got.exact->d_beta_rad, want.exact->d_beta_rad, kAngleTol_rad) << "test " << t;
        EXPECT_NEAR(got.exact->d_gamma_rad, want.exact->d_gamma_rad, kAngleTol_rad) << "test " << t;
        if (got.first_order && want.first_order) {
            EXPECT_NEAR(got.first_order->d_alpha_rad, want.first_order->d_alpha_rad, kAngleTol_rad);
            EXPECT_NEAR(got.first_order->d_beta_rad, want.first_order->d_beta_rad, kAngleTol_rad);
            EXPECT_NEAR(got.first_order->d_gamma_rad, want.first_order->d_gamma_rad, kAngleTol_rad);
        }
        const double angle =
            std::abs(want.exact->d_alpha_rad) + std::abs(want.exact->d_beta_rad) + std::abs(want.exact->d_gamma_rad);
        EXPECT_GT(angle, 1e-5) << "orientation errors must be non-zero";
    }
}

/// Runs a session; every stored point is checked against the machine's true pose.
struct SimRun {
    SimRun(const Plan& plan, SimOptions opt = {}, Answers answers = {}, SimOperatorOptions oo = {},
           SessionOptions so = {})
        : source(setup_for(plan), plan, std::move(opt)), op(&source, std::move(answers), std::move(oo)) {
        sink.check_point = [this](const CapturedPoint& p) { wrong_pose += !window_at_planned_pose(source, p); };
        Session session(plan, source, sink, op, so);
        summary = session.run();
    }
    SimSource source;
    SimOperator op;
    RecordingSink sink;
    SessionSummary summary;
    int wrong_pose = 0;
};

std::size_t count(const RecordingSink& sink, Event e) {
    return static_cast<std::size_t>(
        std::count_if(sink.transitions.begin(), sink.transitions.end(), [e](const auto& t) { return t.event == e; }));
}

class FullProcedure : public ::testing::TestWithParam<MachineType> {};

TEST_P(FullProcedure, RecoversTheInjectedErrorsWithEveryPointAttributedByItsCode) {
    const MachineFile m = seed_machine(GetParam());
    const Plan plan = make_plan(m, default_plan(m));
    SimRun r(plan);
    ASSERT_EQ(r.summary.final_state, State::Done) << r.summary.reason;
    EXPECT_EQ(r.sink.points.size(), plan.points.size());
    EXPECT_EQ(r.wrong_pose, 0);
    EXPECT_EQ(r.sink.discontinuities, 0u);
    EXPECT_EQ(r.summary.programs, 1u);
    EXPECT_EQ(r.summary.void_dwells, 0u);
    ASSERT_EQ(r.op.stops.size(), 1u);  // mount the bar
    EXPECT_NE(r.op.stops[0].find("mount the bar"), std::string::npos);
    for (const auto& p : r.sink.points) EXPECT_NE(p.evidence.find("code "), std::string::npos) << p.evidence;
    expect_matches_truth(plan, r.sink);
    ASSERT_FALSE(r.sink.transitions.empty());
    EXPECT_EQ(r.sink.transitions.front().from, State::Connecting);
    EXPECT_EQ(r.sink.transitions.back().to, State::Done);
}

INSTANTIATE_TEST_SUITE_P(Seed, FullProcedure,
                         ::testing::Values(MachineType::RRTTT, MachineType::TTTRR, MachineType::RTTTR),
                         [](const auto& p) { return std::string(analysis::to_string(p.param)); });

Plan tttrr_plan(int tests = 4) {
    const MachineFile m = seed_machine(MachineType::TTTRR);
    PlanSpec spec = default_plan(m);
    spec.tests.resize(static_cast<std::size_t>(tests));
    return make_plan(m, spec);
}

/// Disconnects at several times during the program (during moves, codes and dwells), 0.2 to 10 s.
class Disconnect : public ::testing::TestWithParam<std::pair<double, double>> {};

TEST_P(Disconnect, NeverStoresAWrongPoseAndRetriesExactlyTheMissingPoints) {
    const Plan plan = tttrr_plan(2);
    SimOptions opt;
    opt.disconnects = {GetParam()};
    SimRun r(plan, opt);
    ASSERT_EQ(r.summary.final_state, State::Done) << r.summary.reason;
    EXPECT_EQ(r.wrong_pose, 0);
    EXPECT_EQ(r.sink.points.size(), plan.points.size());
    EXPECT_EQ(r.summary.pauses, 1u);
    EXPECT_EQ(r.source.references, 2) << "re-referenced after the reconnect";
    EXPECT_EQ(r.summary.programs, 2u);
    // The retry program visits exactly the points the first one did not deliver.
    std::vector<bool> stored_before(plan.points.size(), false);
    const std::size_t first_run = plan.points.size() - r.op.last_points.size();
    for (std::size_t k = 0; k < first_run; ++k)
        stored_before[plan.index(r.sink.points[k].planned.test, r.sink.points[k].planned.step,
                                 r.sink.points[k].planned.point)] = true;
    for (std::size_t i : r.op.last_points) EXPECT_FALSE(stored_before[i]) << "point " << i << " retried twice";
    EXPECT_EQ(r.sink.repeated, 0u);
    expect_matches_truth(plan, r.sink);
}

INSTANTIATE_TEST_SUITE_P(Faults, Disconnect,
                         ::testing::Values(std::pair{12.0, 0.2}, std::pair{14.1, 2.0}, std::pair{16.3, 8.0},
                                           std::pair{20.0, 10.0}, std::pair{25.7, 0.5}, std::pair{31.2, 3.0}),
                         [](const auto& p) {
                             return "at_" + std::to_string(static_cast<int>(p.param.first * 10)) + "_for_" +
                                    std::to_string(static_cast<int>(p.param.second * 10));
                         });

TEST(Session, DroppedAndReplayedFramesNeverMisattribute) {
    const Plan plan = tttrr_plan(2);
    SimOptions opt;
    opt.drop_frame_probability = 0.05;
    opt.replay_frame_probability = 0.02;
    SimRun r(plan, opt);
    ASSERT_EQ(r.summary.final_state, State::Done) << r.summary.reason;
    EXPECT_EQ(r.wrong_pose, 0);
    EXPECT_GT(r.summary.duplicates_dropped, 0u);
    EXPECT_GT(r.summary.gaps, 0u);
    EXPECT_EQ(r.sink.repeated, 0u);
    expect_matches_truth(plan, r.sink);
}

class FeedOverride : public ::testing::TestWithParam<double> {};

TEST_P(FeedOverride, LateStartAndFeedOverrideKeepEveryPointAtItsPose) {
    const Plan plan = tttrr_plan(1);
    SimOperatorOptions oo;
    oo.late_start_s = 60;
    oo.feed_override = GetParam();
    oo.answer_delay_s = [] { return 30.0; };
    SimRun r(plan, {}, {}, oo);
    ASSERT_EQ(r.summary.final_state, State::Done) << r.summary.reason;
    EXPECT_EQ(r.summary.programs, 1u);
    EXPECT_EQ(r.wrong_pose, 0);
    expect_matches_truth(plan, r.sink);
}

INSTANTIATE_TEST_SUITE_P(Override, FeedOverride, ::testing::Values(0.5, 1.0, 1.5),
                         [](const auto& p) { return "percent_" + std::to_string(static_cast<int>(p.param * 100)); });

/// Keeps what the screen is told (Progress) while the program runs.
class ProgressOperator : public SimOperator {
  public:
    using SimOperator::SimOperator;
    void progress(const Progress& p) override { seen.push_back(p); }
    std::vector<Progress> seen;
};

// The countdowns a screen shows: while the machine stands after the cycle start (60 s late here), the
// time until the program's timing runs anyway goes down; once it moves, the point due now has its
// deadline, and the program's time left goes down as it runs, not only at each captured point.
TEST(Session, TheScreensCountdownsRunWhileTheMachineStandsAndWhileItMoves) {
    const Plan plan = tttrr_plan(1);
    SimOperatorOptions oo;
    oo.late_start_s = 60;
    SimSource source(setup_for(plan), plan, {});
    ProgressOperator op(&source, {}, oo);
    RecordingSink sink;
    Session session(plan, source, sink, op, {});
    ASSERT_EQ(session.run().final_state, State::Done);
    std::vector<double> waits, left_while_moving;
    bool due_seen = false;
    for (const Progress& p : op.seen) {
        EXPECT_FALSE(p.start_wait_left_s && p.point_due_s) << "one countdown at a time";
        if (p.start_wait_left_s) waits.push_back(*p.start_wait_left_s);
        if (p.point_due_s) {
            due_seen = true;
            EXPECT_GE(*p.point_due_s, 0.0);
            if (p.done == 0) left_while_moving.push_back(p.time_left_s);
        }
    }
    ASSERT_GE(waits.size(), 10u) << "the machine stood 60 s: the start countdown was shown";
    EXPECT_LE(waits.front(), SessionOptions{}.max_standstill_s);
    EXPECT_LT(waits.back(), waits.front() - 50) << "it went down through the 60 s the machine stood";
    EXPECT_TRUE(std::is_sorted(waits.rbegin(), waits.rend()));
    EXPECT_TRUE(due_seen);
    ASSERT_GE(left_while_moving.size(), 3u);
    EXPECT_LT(left_while_moving.back(), left_while_moving.front()) << "the time left counts down before a point";
}

/// The operator loads the wrong program at the retry (the full one): its dwells name points the retry
/// does not ask for, or that are stored already; none is stored again or elsewhere.
class WrongProgramOperator : public SimOperator {
  public:
    WrongProgramOperator(SimSource* s, const Plan& plan) : SimOperator(s), plan_(plan) {}
    void run_program(const analysis::NcProgram& program, std::span<const std::size_t> points, bool retry) override {
        if (!retry || wrong_done_) return SimOperator::run_program(program, points, retry);
        wrong_done_ = true;
        const auto all = points_from(plan_, 0);
        SimOperator::run_program(make_measuring_program(plan_, all).nc, points, retry);
    }

  private:
    const Plan& plan_;
    bool wrong_done_ = false;
};

TEST(Session, ARetryRunWithTheWrongProgramStoresNothingTwiceNorElsewhere) {
    const Plan plan = tttrr_plan(2);
    SimOptions opt;
    opt.disconnects = {{14.0, 1.0}};
    SimSource source(setup_for(plan), plan, opt);
    WrongProgramOperator op(&source, plan);
    RecordingSink sink;
    int wrong = 0;
    sink.check_point = [&](const CapturedPoint& p) { wrong += !window_at_planned_pose(source, p); };
    Session session(plan, source, sink, op);
    const SessionSummary sum = session.run();
    ASSERT_EQ(sum.final_state, State::Done) << sum.reason;
    EXPECT_EQ(wrong, 0);
    EXPECT_EQ(sink.points.size(), plan.points.size());
    EXPECT_GE(sum.programs, 2u);
    expect_matches_truth(plan, sink);
}

TEST(Session, AMachineThatNeverStartsEndsInterruptedWithEveryPointMissing) {
    const Plan plan = tttrr_plan(1);
    SimSource source(setup_for(plan), plan, {});
    class Idle : public SimOperator {
      public:
        using SimOperator::SimOperator;
        void run_program(const analysis::NcProgram&, std::span<const std::size_t>, bool) override { ++programs; }
    } op(&source);
    RecordingSink sink;
    SessionOptions so;
    so.max_programs = 2;
    Session session(plan, source, sink, op, so);
    const SessionSummary sum = session.run();
    EXPECT_EQ(sum.final_state, State::Aborted);
    EXPECT_TRUE(sum.interrupted);
    EXPECT_EQ(sum.missing.size(), plan.points.size());
    EXPECT_EQ(op.programs, 2);
    // Each program: the standstill allowed after its start, the grace, then the program's own timing.
    EXPECT_LT(source.now_s(), 2 * (so.max_standstill_s + so.start_grace_s + 200))
        << "the waits follow the program's timing";
}

/// Issue 24: an instrument that stays plugged in but stops answering (the emulator's stall) made
/// every reconnect attempt last its reply timeouts, so 600 attempts "of 0.2 s" took many minutes in
/// silence. The wait is bounded in wall time (attempts × read timeout) and told to the operator: the
/// bound at the start, the time left while it lasts.
TEST(Session, AnInstrumentThatStopsAnsweringEndsTheWaitInBoundedTimeAndSaysSo) {
    const Plan plan = tttrr_plan(1);
    SimOptions opt;
    opt.referenced = true;
    class Mute : public SimSource {
      public:
        using SimSource::SimSource;
        void start() override { throw SourceError("no reply to Start"); }
        bool reconnect(std::chrono::milliseconds) override {
            ++attempts;
            std::this_thread::sleep_for(std::chrono::milliseconds(30));  // its reply timeouts
            return false;
        }
        int attempts = 0;
    } source(setup_for(plan), plan, opt);
    class Listening : public SimOperator {
      public:
        using SimOperator::SimOperator;
        void message(std::string_view text) override { said.emplace_back(text); }
        std::vector<std::string> said;
    } op(&source);
    RecordingSink sink;
    SessionOptions so;
    so.read_timeout = std::chrono::milliseconds(10);
    so.max_reconnect_attempts = 100;  // bound: 100 × 10 ms = 1 s, where 100 attempts take 3 s
    Session session(plan, source, sink, op, so);
    const SessionSummary sum = session.run();
    EXPECT_TRUE(sum.interrupted);
    EXPECT_NE(sum.reason.find("did not come back within 1 s"), std::string::npos) << sum.reason;
    EXPECT_LT(source.attempts, 60) << "the wall-time bound ends the wait, not the attempts";
    ASSERT_FALSE(op.said.empty());
    const bool told = std::any_of(op.said.begin(), op.said.end(), [](const std::string& m) {
        return m.find("Waiting for the instrument to answer (at most 1 s") != std::string::npos;
    });
    EXPECT_TRUE(told) << op.said.front();
}

TEST(Session, KilledSessionResumesWithAProgramForTheMissingPointsOnly) {
    const Plan plan = tttrr_plan(2);
    RecordingSink first;
    first.kill_after_points = 5;
    {
        SimSource source(setup_for(plan), plan, SimOptions{});
        SimOperator op(&source);
        Session session(plan, source, first, op);
        EXPECT_THROW(session.run(), RecordingSink::Killed);
    }
    ASSERT_EQ(first.points.size(), 5u);
    SimOptions opt;
    opt.seed = 99;
    SimSource source(setup_for(plan, 5), plan, opt);
    RecordingSink second;
    SimOperator op(&source);
    Session session(plan, source, second, op);
    session.restore(first.points);
    EXPECT_EQ(session.missing().size(), plan.points.size() - 5);
    const SessionSummary sum = session.run();
    ASSERT_EQ(sum.final_state, State::Done) << sum.reason;
    EXPECT_EQ(second.points.size(), plan.points.size() - 5);
    EXPECT_EQ(op.last_points.size(), plan.points.size() - 5);
    EXPECT_EQ(op.last_points.front(), 5u);
    RecordingSink merged = second;
    merged.points.insert(merged.points.begin(), first.points.begin(), first.points.end());
    std::sort(merged.points.begin(), merged.points.end(), [&](const auto& a, const auto& b) {
        return plan.index(a.planned.test, a.planned.step, a.planned.point) <
               plan.index(b.planned.test, b.planned.step, b.planned.point);
    });
    expect_matches_truth(plan, merged);
}

TEST(Session, FailedPointIsMeasuredAgainThenTheOperatorDecides) {
    const MachineFile m = seed_machine(MachineType::TTTRR);
    PlanSpec spec = default_plan(m);
    spec.tests.resize(1);
    spec.capture.max_std_mm = 0.00005;  // 0.05 µm: the 0.1 µm noise fails every point
    spec.capture.retries = 1;
    const Plan plan = make_plan(m, spec);
    Answers answers;
    answers.on_point_failure = PointFailureAction::Abort;
    SimRun r(plan, {}, answers);
    EXPECT_EQ(r.summary.final_state, State::Aborted);
    EXPECT_FALSE(r.summary.interrupted);
    EXPECT_EQ(r.summary.programs, 2u) << "one retry program, then the operator is asked";
    EXPECT_NE(r.summary.reason.find("std"), std::string::npos) << r.summary.reason;
    EXPECT_TRUE(r.sink.points.empty());
}

TEST(Session, OperatorMayAcceptAFailedPointWhichKeepsItsAttribution) {
    const MachineFile m = seed_machine(MachineType::TTTRR);
    PlanSpec spec = default_plan(m);
    spec.tests.resize(1);
    spec.capture.max_std_mm = 0.00005;
    spec.capture.retries = 0;
    const Plan plan = make_plan(m, spec);
    Answers answers;
    answers.on_point_failure = PointFailureAction::Accept;
    SimRun r(plan, {}, answers);
    ASSERT_EQ(r.summary.final_state, State::Done) << r.summary.reason;
    ASSERT_EQ(r.sink.points.size(), plan.points.size());
    EXPECT_EQ(r.wrong_pose, 0);
    for (const auto& p : r.sink.points) EXPECT_TRUE(p.operator_accepted);
}

TEST(Session, WrongBarLengthFailsBeforeTheOperatorIsAskedAnything) {
    const MachineFile m = seed_machine(MachineType::TTTRR);
    PlanSpec spec = default_plan(m);
    spec.bar_length_mm = 150;
    const Plan plan = make_plan(m, spec);
    const Plan plan100 = make_plan(m, default_plan(m));
    SimSource source(setup_for(plan100), plan100, SimOptions{});  // a 100 mm bar
    RecordingSink sink;
    SimOperator op(&source);
    Session session(plan, source, sink, op);
    const SessionSummary sum = session.run();
    EXPECT_EQ(sum.final_state, State::Failed);
    EXPECT_NE(sum.reason.find("calibrated at"), std::string::npos) << sum.reason;
    EXPECT_NE(sum.reason.find("\"bar_length_mm\": 100"), std::string::npos) << sum.reason;
    EXPECT_TRUE(op.asked.empty());
}

TEST(Session, DeclinedSetUpAborts) {
    const MachineFile m = seed_machine(MachineType::RTTTR);
    const Plan plan = make_plan(m, default_plan(m));
    Answers answers;
    answers.confirm_setup = false;
    SimRun r(plan, {}, answers);
    EXPECT_EQ(r.summary.final_state, State::Aborted);
    EXPECT_TRUE(r.sink.points.empty());
}

TEST(Session, RejectedResultsMeasureEveryPointAgain) {
    const Plan plan = tttrr_plan(1);
    SimSource source(setup_for(plan), plan, {});
    class Picky : public SimOperator {
      public:
        using SimOperator::SimOperator;
        std::size_t choose(const Choice& c) override {
            if (c.what == "review") {
                prompts.push_back(c.prompt);
                return reviews++ == 0 ? 1 : 0;  // measure again, then accept
            }
            return SimOperator::choose(c);
        }
        int reviews = 0;
        std::vector<std::string> prompts;
    } op(&source);
    RecordingSink sink;
    Session session(plan, source, sink, op);
    const SessionSummary sum = session.run();
    ASSERT_EQ(sum.final_state, State::Done) << sum.reason;
    EXPECT_EQ(op.reviews, 2);
    EXPECT_EQ(sink.points.size(), 2 * plan.points.size());
    EXPECT_EQ(sum.programs, 2u);
    ASSERT_FALSE(op.prompts.empty());
    EXPECT_NE(op.prompts[0].find("ΔV1"), std::string::npos) << "the results are shown before they are accepted";
    EXPECT_NE(op.prompts[0].find("Δγ"), std::string::npos);
    EXPECT_EQ(op.prompts[0].find("Δβ"), std::string::npos) << "a TTTRR has no Δβ";
}

TEST(Session, MultiSocketPlanStopsForEveryRemountAndRunsToTheEnd) {
    const MachineFile m = seed_machine(MachineType::TTTRR);
    PlanSpec spec = default_plan(m);
    spec.tests.resize(3);
    spec.tests[1].socket_mm = spec.tests[0].socket_mm + analysis::Vec3(30, 0, 0);
    spec.tests[2].socket_mm = spec.tests[0].socket_mm + analysis::Vec3(0, 25, 10);
    const Plan plan = make_plan(m, spec);
    SimRun r(plan);
    ASSERT_EQ(r.summary.final_state, State::Done) << r.summary.reason;
    EXPECT_EQ(r.wrong_pose, 0);
    EXPECT_EQ(r.sink.points.size(), plan.points.size());
    ASSERT_EQ(r.op.stops.size(), 5u);  // mount; then for each new position: move the socket, mount
    EXPECT_NE(r.op.stops[1].find("move the socket"), std::string::npos) << r.op.stops[1];
    EXPECT_NE(r.op.stops[2].find("mount the bar"), std::string::npos) << r.op.stops[2];
    EXPECT_EQ(count(r.sink, Event::ProgramStopReached), 5u);
    expect_matches_truth(plan, r.sink);
}

/// Ctrl-C (the stop flag) just after the last test's result: only the review question would follow.
class StopAfterLastTest : public RecordingSink {
  public:
    StopAfterLastTest(std::atomic<bool>& stop, std::size_t test_count) : stop_(stop), tests_(test_count) {}
    void on_test(const TestResult& r) override {
        RecordingSink::on_test(r);
        if (tests.size() == tests_) stop_.store(true);
    }

  private:
    std::atomic<bool>& stop_;
    std::size_t tests_;
};

TEST(Session, CtrlCBeforeAPromptEndsTheSessionWithoutAskingIt) {
    const Plan plan = tttrr_plan(2);
    SimSource source(setup_for(plan), plan, SimOptions{});
    std::atomic<bool> stop{false};
    StopAfterLastTest sink(stop, static_cast<std::size_t>(plan.test_count()));
    SimOperator op(&source);
    SessionOptions options;
    options.stop = &stop;
    Session session(plan, source, sink, op, options);
    const SessionSummary sum = session.run();
    EXPECT_EQ(sum.final_state, State::Aborted);
    EXPECT_TRUE(sum.interrupted);
    EXPECT_EQ(sum.reason, "interrupted by the operator");
    EXPECT_EQ(std::count(op.asked.begin(), op.asked.end(), "review"), 0) << "the results were not offered";
    EXPECT_EQ(sink.points.size(), plan.points.size()) << "what was captured is kept";
}

}  // namespace
}  // namespace ballbar::acquisition

namespace ballbar::acquisition {
namespace {

/// Points of an interrupted session restored but for one: the retry program of that single point
/// measures it, for every type and for the first and the last point of the plan.
class SinglePointRetry : public ::testing::TestWithParam<std::tuple<MachineType, bool>> {};

TEST_P(SinglePointRetry, MeasuresExactlyThatPoint) {
    const auto [type, last] = GetParam();
    const MachineFile m = seed_machine(type);
    const Plan plan = make_plan(m, default_plan(m));
    const std::size_t target = last ? plan.points.size() - 1 : 0;
    std::vector<CapturedPoint> done;
    {
        SimRun full(plan);
        ASSERT_EQ(full.summary.final_state, State::Done);
        for (const auto& p : full.sink.points)
            if (plan.index(p.planned.test, p.planned.step, p.planned.point) != target) done.push_back(p);
    }
    SimSource source(setup_for(plan, (target + 5) % plan.points.size()), plan, {});
    SimOperator op(&source);
    RecordingSink sink;
    int wrong = 0;
    sink.check_point = [&](const CapturedPoint& p) { wrong += !window_at_planned_pose(source, p); };
    Session session(plan, source, sink, op);
    session.restore(done);
    const SessionSummary sum = session.run();
    ASSERT_EQ(sum.final_state, State::Done) << sum.reason;
    ASSERT_EQ(sink.points.size(), 1u);
    EXPECT_EQ(wrong, 0);
    EXPECT_EQ(plan.index(sink.points[0].planned.test, sink.points[0].planned.step, sink.points[0].planned.point),
              target);
    EXPECT_EQ(op.stops.size(), 2u);  // remove the bar; mount it
}

INSTANTIATE_TEST_SUITE_P(Types, SinglePointRetry,
                         ::testing::Combine(::testing::Values(MachineType::RRTTT, MachineType::TTTRR,
                                                              MachineType::RTTTR),
                                            ::testing::Bool()),
                         [](const auto& p) {
                             return std::string(analysis::to_string(std::get<0>(p.param))) +
                                    (std::get<1>(p.param) ? "_LastPoint" : "_FirstPoint");
                         });

}  // namespace
}  // namespace ballbar::acquisition
