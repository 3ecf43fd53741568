// SPDX-License-Identifier: MIT
#include "ballbar/acquisition/state_machine.hpp"

#include <array>

namespace ballbar::acquisition {
namespace {

constexpr std::array<std::string_view, kStateCount> kStateNames = {
    "Connecting", "InstrumentCheck", "SetUp", "Running", "ProgramStop", "Retry",
    "Computing",  "Review",          "Done",  "Paused",  "Aborted",     "Failed",
};
constexpr std::array<std::string_view, kEventCount> kEventNames = {
    "Connected",  "CheckPassed",  "SetUpConfirmed",    "PointCaptured", "PointRejected", "ProgramStopReached",
    "CycleStart", "ProgramEnded", "AllPointsCaptured", "RetryStarted",  "ResultsReady",  "Accepted",
    "Rejected",   "DeviceLost",   "DeviceBack",        "Abort",         "Fail",
};

/// States in which the instrument is in use, so losing it pauses the session.
bool uses_device(State s) {
    switch (s) {
        case State::InstrumentCheck:
        case State::SetUp:
        case State::Running:
        case State::ProgramStop:
        case State::Retry:
            return true;
        default:
            return false;
    }
}

}  // namespace

std::string_view to_string(State s) {
    return kStateNames[static_cast<std::size_t>(s)];
}
std::string_view to_string(Event e) {
    return kEventNames[static_cast<std::size_t>(e)];
}

std::optional<State> parse_state(std::string_view text) {
    for (int i = 0; i < kStateCount; ++i)
        if (kStateNames[static_cast<std::size_t>(i)] == text) return static_cast<State>(i);
    return std::nullopt;
}

bool is_terminal(State s) {
    return s == State::Done || s == State::Aborted || s == State::Failed;
}

TransitionError::TransitionError(State state, Event event)
    : std::logic_error("event " + std::string(to_string(event)) + " is not allowed in state " +
                       std::string(to_string(state))),
      state_(state),
      event_(event) {}

std::optional<State> transition(State state, Event event, State paused_from) {
    if (is_terminal(state)) return std::nullopt;
    // Events every live state shares.
    if (event == Event::Abort) return State::Aborted;
    if (event == Event::Fail) return State::Failed;
    if (event == Event::DeviceLost) return uses_device(state) ? std::optional(State::Paused) : std::nullopt;

    using S = State;
    using E = Event;
    switch (state) {
        case S::Connecting:
            if (event == E::Connected) return S::InstrumentCheck;
            break;
        case S::InstrumentCheck:
            if (event == E::CheckPassed) return S::SetUp;
            break;
        case S::SetUp:
            if (event == E::SetUpConfirmed) return S::Running;
            break;
        case S::Running:
            if (event == E::PointCaptured || event == E::PointRejected) return S::Running;
            if (event == E::ProgramStopReached) return S::ProgramStop;
            if (event == E::ProgramEnded) return S::Retry;
            if (event == E::AllPointsCaptured) return S::Computing;
            break;
        case S::ProgramStop:
            if (event == E::CycleStart) return S::Running;
            if (event == E::ProgramEnded) return S::Retry;
            break;
        case S::Retry:
            if (event == E::RetryStarted) return S::Running;
            if (event == E::PointCaptured) return S::Retry;  // a failed point the operator kept
            if (event == E::AllPointsCaptured) return S::Computing;
            break;
        case S::Computing:
            if (event == E::ResultsReady) return S::Review;
            break;
        case S::Review:
            if (event == E::Accepted) return S::Done;
            if (event == E::Rejected) return S::Running;
            break;
        case S::Paused:
            if (event == E::DeviceBack) return paused_from;
            break;
        case S::Done:
        case S::Aborted:
        case S::Failed:
            break;
    }
    return std::nullopt;
}

State StateMachine::apply(Event event) {
    const auto next = transition(state_, event, paused_from_);
    if (!next) throw TransitionError(state_, event);
    if (*next == State::Paused) paused_from_ = state_;
    state_ = *next;
    return state_;
}

}  // namespace ballbar::acquisition
