// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "ballbar/acquisition/state_machine.hpp"

namespace ballbar::acquisition {
namespace {

TEST(StateMachine, HappyPathWithAStopAndARetry) {
    StateMachine sm;
    for (Event e :
         {Event::Connected, Event::CheckPassed, Event::SetUpConfirmed, Event::PointCaptured, Event::PointRejected,
          Event::ProgramStopReached, Event::CycleStart, Event::PointCaptured, Event::ProgramEnded, Event::RetryStarted,
          Event::PointCaptured, Event::AllPointsCaptured, Event::ResultsReady, Event::Accepted})
        sm.apply(e);
    EXPECT_EQ(sm.state(), State::Done);
}

TEST(StateMachine, RejectedResultsMeasureAgain) {
    StateMachine sm(State::Review);
    EXPECT_EQ(sm.apply(Event::Rejected), State::Running);
}

TEST(StateMachine, PauseReturnsToTheStateItCameFrom) {
    for (State s : {State::InstrumentCheck, State::SetUp, State::Running, State::ProgramStop, State::Retry}) {
        StateMachine sm(s);
        EXPECT_EQ(sm.apply(Event::DeviceLost), State::Paused);
        EXPECT_EQ(sm.paused_from(), s);
        EXPECT_EQ(sm.apply(Event::DeviceBack), s);
    }
}

TEST(StateMachine, AbortAndFailFromEveryLiveState) {
    for (int i = 0; i < kStateCount; ++i) {
        const auto s = static_cast<State>(i);
        if (is_terminal(s)) continue;
        EXPECT_EQ(StateMachine(s).apply(Event::Abort), State::Aborted) << to_string(s);
        EXPECT_EQ(StateMachine(s).apply(Event::Fail), State::Failed) << to_string(s);
    }
}

TEST(StateMachine, NamesRoundTrip) {
    for (int i = 0; i < kStateCount; ++i) {
        const auto s = static_cast<State>(i);
        EXPECT_EQ(parse_state(to_string(s)), s);
    }
    EXPECT_FALSE(parse_state("Flying"));
}

// One test per illegal (state, event) pair.
struct Pair {
    State state;
    Event event;
};

std::vector<Pair> illegal_pairs() {
    std::vector<Pair> out;
    for (int s = 0; s < kStateCount; ++s)
        for (int e = 0; e < kEventCount; ++e) {
            const auto st = static_cast<State>(s);
            const auto ev = static_cast<Event>(e);
            // Paused's target depends on where it came from; judge it with a realistic origin.
            if (!transition(st, ev, State::Running)) out.push_back({st, ev});
        }
    return out;
}

class IllegalTransition : public ::testing::TestWithParam<Pair> {};

TEST_P(IllegalTransition, IsRefusedNamingStateAndEvent) {
    const Pair p = GetParam();
    StateMachine sm(p.state);
    try {
        sm.apply(p.event);
        FAIL() << "accepted " << to_string(p.event) << " in " << to_string(p.state);
    } catch (const TransitionError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(std::string(to_string(p.state))), std::string::npos) << msg;
        EXPECT_NE(msg.find(std::string(to_string(p.event))), std::string::npos) << msg;
        EXPECT_EQ(e.state(), p.state);
        EXPECT_EQ(e.event(), p.event);
    }
    EXPECT_EQ(sm.state(), p.state);  // unchanged
}

INSTANTIATE_TEST_SUITE_P(AllPairs, IllegalTransition, ::testing::ValuesIn(illegal_pairs()),
                         [](const ::testing::TestParamInfo<Pair>& p) {
                             return std::string(to_string(p.param.state)) + "_" + std::string(to_string(p.param.event));
                         });

TEST(StateMachine, IllegalPairsAreMostOfTheTable) {
    // 13 states × 14 events; the legal ones are the graph of docs/procedure.md.
    const auto n = illegal_pairs().size();
    EXPECT_GT(n, 120u);
    EXPECT_LT(n, static_cast<std::size_t>(kStateCount * kEventCount));
}

}  // namespace
}  // namespace ballbar::acquisition
