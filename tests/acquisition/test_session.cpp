// SPDX-License-Identifier: MIT
// The whole procedure against a simulated machine with injected errors (device::SimulatedMachine runs
// the plan's NC program; the bar reads it at 1 kHz with 0.1 µm noise). "True" values: the exact total
// position error (b − s)_actual − (b − s)_nominal of the machine's kinematics at the planned points, and
// the orientation errors the same (exact) orientation model gives for those exact errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>

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

class TestOperator : public ScriptedOperator {
  public:
    TestOperator(const Plan& plan, SimSource* source, Answers answers = {})
        : ScriptedOperator(std::move(answers)), plan_(plan), source_(source) {}
    void run_program(std::size_t from) override {
        ++restarts;
        if (!source_) return;
        auto& m = source_->machine();
        m.stop(source_->now_s());
        m.run_program(make_nc_program(plan_, from));
    }
    int restarts = 0;

  private:
    const Plan& plan_;
    SimSource* source_;
};

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

class FullProcedure : public ::testing::TestWithParam<MachineType> {};

TEST_P(FullProcedure, RecoversTheInjectedErrors) {
    const MachineFile m = seed_machine(GetParam());
    const Plan plan = make_plan(m, default_plan(m));
    SimSource source(setup_for(plan), plan, SimOptions{});
    RecordingSink sink;
    TestOperator op(plan, &source);
    Session session(plan, source, sink, op);
    const SessionSummary sum = session.run();
    ASSERT_EQ(sum.final_state, State::Done) << sum.reason;
    EXPECT_EQ(sink.points.size(), plan.points.size());
    EXPECT_EQ(sink.discontinuities, 0u);
    EXPECT_EQ(sum.gaps, 0u);
    expect_matches_truth(plan, sink);
    // The audit trail starts at Connecting and ends in Done.
    ASSERT_FALSE(sink.transitions.empty());
    EXPECT_EQ(sink.transitions.front().from, State::Connecting);
    EXPECT_EQ(sink.transitions.back().to, State::Done);
}

INSTANTIATE_TEST_SUITE_P(Seed, FullProcedure,
                         ::testing::Values(MachineType::RRTTT, MachineType::TTTRR, MachineType::RTTTR),
                         [](const auto& p) { return std::string(analysis::to_string(p.param)); });

TEST(Session, DisconnectPausesAndContinuesAtTheSamePointWithoutLosingOrRepeatingSamples) {
    const MachineFile m = seed_machine(MachineType::TTTRR);
    const Plan plan = make_plan(m, default_plan(m));
    SimOptions opt;
    opt.disconnect_after = 9000;  // inside test 1
    opt.repeat_after_reconnect = 40;
    SimSource source(setup_for(plan), plan, opt);
    RecordingSink sink;
    TestOperator op(plan, &source);
    Session session(plan, source, sink, op);
    const SessionSummary sum = session.run();
    ASSERT_EQ(sum.final_state, State::Done) << sum.reason;
    EXPECT_EQ(sum.pauses, 1u);
    EXPECT_EQ(op.restarts, 2);  // cycle start and the restart after the pause
    EXPECT_EQ(sum.duplicates_dropped, 40u);
    EXPECT_EQ(sink.discontinuities, 0u);
    EXPECT_EQ(sink.samples, source.produced());  // every sample stored, once
    bool paused = false, back = false;
    for (const auto& t : sink.transitions) {
        paused |= t.event == Event::DeviceLost && t.to == State::Paused;
        back |= t.event == Event::DeviceBack;
    }
    EXPECT_TRUE(paused && back);
    ASSERT_EQ(sink.points.size(), plan.points.size());
    for (std::size_t i = 0; i < plan.points.size(); ++i) {
        EXPECT_EQ(sink.points[i].planned.point, plan.points[i].point);
        EXPECT_EQ(sink.points[i].planned.step, plan.points[i].step);
    }
    expect_matches_truth(plan, sink);
}

TEST(Session, KilledSessionResumesAfterTheLastCompletedPoint) {
    const MachineFile m = seed_machine(MachineType::RRTTT);
    const Plan plan = make_plan(m, default_plan(m));
    RecordingSink first;
    first.kill_after_points = 10;
    {
        SimSource source(setup_for(plan), plan, SimOptions{});
        TestOperator op(plan, &source);
        Session session(plan, source, first, op);
        EXPECT_THROW(session.run(), RecordingSink::Killed);
    }
    ASSERT_EQ(first.points.size(), 10u);
    // A new process: the stored points, a program from point 10, a new stream.
    SimOptions opt;
    opt.seed = 99;
    SimSource source(setup_for(plan, 10), plan, opt);
    RecordingSink second;
    TestOperator op(plan, &source);
    Session session(plan, source, second, op);
    session.restore(first.points);
    EXPECT_EQ(session.next_point(), 10u);
    const SessionSummary sum = session.run();
    ASSERT_EQ(sum.final_state, State::Done) << sum.reason;
    EXPECT_EQ(second.points.size(), plan.points.size() - 10);
    EXPECT_EQ(second.points.front().planned.test, plan.points[10].test);
    EXPECT_EQ(second.points.front().planned.step, plan.points[10].step);
    EXPECT_EQ(second.points.front().planned.point, plan.points[10].point);
    // Results of every test, including the ones whose points were all measured before the kill.
    RecordingSink merged = second;
    merged.points.insert(merged.points.begin(), first.points.begin(), first.points.end());
    expect_matches_truth(plan, merged);
}

TEST(Session, FailedPointIsCapturedAgainThenTheOperatorDecides) {
    const MachineFile m = seed_machine(MachineType::TTTRR);
    PlanSpec spec = default_plan(m);
    spec.tests.resize(1);
    spec.capture.max_std_mm = 0.00005;  // 0.05 µm: the 0.1 µm noise fails every point
    spec.capture.retries = 1;
    const Plan plan = make_plan(m, spec);
    SimSource source(setup_for(plan), plan, SimOptions{});
    RecordingSink sink;
    Answers answers;
    answers.on_point_failure = PointFailureAction::Abort;
    TestOperator op(plan, &source, answers);
    Session session(plan, source, sink, op);
    const SessionSummary sum = session.run();
    EXPECT_EQ(sum.final_state, State::Aborted);
    EXPECT_EQ(sum.recaptures, 1u);
    EXPECT_NE(sum.reason.find("std"), std::string::npos) << sum.reason;
    int rejected = 0;
    for (const auto& t : sink.transitions) rejected += t.event == Event::PointRejected;
    EXPECT_EQ(rejected, 2);
}

TEST(Session, OperatorMayAcceptAFailedPoint) {
    const MachineFile m = seed_machine(MachineType::TTTRR);
    PlanSpec spec = default_plan(m);
    spec.tests.resize(1);
    spec.capture.max_std_mm = 0.00005;
    spec.capture.retries = 0;
    const Plan plan = make_plan(m, spec);
    SimSource source(setup_for(plan), plan, SimOptions{});
    RecordingSink sink;
    Answers answers;
    answers.on_point_failure = PointFailureAction::Accept;
    TestOperator op(plan, &source, answers);
    Session session(plan, source, sink, op);
    EXPECT_EQ(session.run().final_state, State::Done);
    ASSERT_EQ(sink.points.size(), plan.points.size());
    EXPECT_TRUE(sink.points.front().operator_accepted);
}

TEST(Session, WrongBarLengthFailsTheInstrumentCheck) {
    const MachineFile m = seed_machine(MachineType::TTTRR);
    PlanSpec spec = default_plan(m);
    spec.bar_length_mm = 150;
    const Plan plan = make_plan(m, spec);
    PlanSpec other = default_plan(m);
    const Plan plan100 = make_plan(m, other);
    SimSource source(setup_for(plan100), plan100, SimOptions{});  // a 100 mm bar
    RecordingSink sink;
    TestOperator op(plan, &source);
    Session session(plan, source, sink, op);
    const SessionSummary sum = session.run();
    EXPECT_EQ(sum.final_state, State::Failed);
    EXPECT_NE(sum.reason.find("calibrated length"), std::string::npos) << sum.reason;
}

TEST(Session, DeclinedSetUpAborts) {
    const MachineFile m = seed_machine(MachineType::RTTTR);
    const Plan plan = make_plan(m, default_plan(m));
    SimSource source(setup_for(plan), plan, SimOptions{});
    RecordingSink sink;
    Answers answers;
    answers.confirm_setup = false;
    TestOperator op(plan, &source, answers);
    Session session(plan, source, sink, op);
    EXPECT_EQ(session.run().final_state, State::Aborted);
    EXPECT_TRUE(sink.points.empty());
}

/// An operator who records the questions it is asked.
class AskedOperator : public TestOperator {
  public:
    using TestOperator::TestOperator;
    bool confirm(std::string_view what, std::string_view prompt) override {
        asked.emplace_back(what);
        return TestOperator::confirm(what, prompt);
    }
    std::vector<std::string> asked;
};

/// Ctrl-C (the stop flag) just after the last test's result: no read of the instrument follows, only
/// the question whether to accept the results.
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
    const MachineFile m = seed_machine(MachineType::TTTRR);
    const Plan plan = make_plan(m, default_plan(m));
    SimSource source(setup_for(plan), plan, SimOptions{});
    std::atomic<bool> stop{false};
    StopAfterLastTest sink(stop, static_cast<std::size_t>(plan.test_count()));
    AskedOperator op(plan, &source);
    SessionOptions options;
    options.stop = &stop;
    Session session(plan, source, sink, op, options);
    const SessionSummary sum = session.run();
    EXPECT_EQ(sum.final_state, State::Aborted);
    EXPECT_TRUE(sum.interrupted);
    EXPECT_EQ(sum.reason, "interrupted by the operator");
    EXPECT_EQ(std::count(op.asked.begin(), op.asked.end(), "accept"), 0) << "the results were not offered";
    EXPECT_EQ(sink.points.size(), plan.points.size()) << "what was captured is kept";
}

}  // namespace
}  // namespace ballbar::acquisition
