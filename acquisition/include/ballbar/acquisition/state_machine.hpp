// SPDX-License-Identifier: MIT
// The guided two-step SSM procedure as an explicit state machine: one enum of states, one enum of
// events, one transition function. Every event is checked against the current state; an illegal one is
// refused with an error naming both. docs/procedure.md draws the graph.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace ballbar::acquisition {

enum class State {
    Connecting,       ///< opening the instrument
    InstrumentCheck,  ///< battery, temperature, reference set on the calibrator, bar length
    SetUp,            ///< machine type and geometry, socket position, bar length, layout
    Running,          ///< an NC program runs; its dwells are attributed to points and captured
    ProgramStop,      ///< the program waits at a program stop (M0) while the operator acts
    Retry,            ///< a program ended with points missing; the operator decides on a retry program
    Computing,        ///< SSM and the orientation model of every test
    Review,           ///< the operator reviews the results
    Done,
    Paused,   ///< the instrument was lost; continues when it is back (and re-referenced)
    Aborted,  ///< stopped by the operator (or interrupted: resumable)
    Failed,   ///< cannot continue (instrument check failed, instrument gone for good, computation failed)
};
constexpr int kStateCount = static_cast<int>(State::Failed) + 1;

enum class Event {
    Connected,           ///< the instrument answered
    CheckPassed,         ///< battery, temperature, reference and bar length are fine
    SetUpConfirmed,      ///< the operator confirmed the set-up and was told to start the program
    PointCaptured,       ///< a dwell was attributed to its point and passed its checks: stored
    PointRejected,       ///< a dwell was void (not attributable) or failed its checks: not stored
    ProgramStopReached,  ///< the program reached a program stop; the operator is asked to act
    CycleStart,          ///< the operator acted and pressed cycle start
    ProgramEnded,        ///< the program ended (or timed out, or was abandoned) with points missing
    AllPointsCaptured,   ///< every planned point is captured
    RetryStarted,        ///< the operator runs a program for the missing points
    ResultsReady,        ///< every test is computed
    Accepted,            ///< the operator accepted the results
    Rejected,            ///< the operator rejected the results: every point is measured again
    DeviceLost,          ///< the link to the instrument went away
    DeviceBack,          ///< the instrument is back and re-referenced
    Abort,               ///< the operator stopped the session
    Fail,                ///< an unrecoverable error
};
constexpr int kEventCount = static_cast<int>(Event::Fail) + 1;

std::string_view to_string(State s);
std::string_view to_string(Event e);
std::optional<State> parse_state(std::string_view text);
bool is_terminal(State s);

/// Refused event: "event PointCaptured is not allowed in state SetUp".
class TransitionError : public std::logic_error {
  public:
    TransitionError(State state, Event event);
    State state() const { return state_; }
    Event event() const { return event_; }

  private:
    State state_;
    Event event_;
};

/// The transition function. `paused_from` is the state a Paused session goes back to on DeviceBack
/// (ignored elsewhere). Returns nullopt when the event is illegal in `state`.
std::optional<State> transition(State state, Event event, State paused_from = State::Connecting);

/// Holds the current state and applies events through `transition`, remembering where a pause came
/// from. Throws TransitionError for an illegal event and leaves the state unchanged.
class StateMachine {
  public:
    explicit StateMachine(State initial = State::Connecting) : state_(initial) {}
    State state() const { return state_; }
    /// Applies `event` and returns the new state.
    State apply(Event event);
    bool can_apply(Event event) const { return transition(state_, event, paused_from_).has_value(); }
    State paused_from() const { return paused_from_; }

  private:
    State state_;
    State paused_from_ = State::Connecting;
};

}  // namespace ballbar::acquisition
