// SPDX-License-Identifier: MIT
// The circular test (ISO 230-4) as a guided procedure on the same mechanism as the SSM one: the same
// state machine (state_machine.hpp), the same SampleSource and Operator, transitions and samples to a
// sink as they happen (docs/procedure.md, "The circular test").
//
// Instrument check (bar length against the test radius, the feed-in within the transducer's range, the
// feed against the instrument's rate), reference in the calibrator, set-up (mount the bar between the
// socket at the circle centre and the tool ball), then the part program: the stream runs while the
// machine runs it; each run's feed-in is found in the data with the analysis's run finder, and a run is
// captured once the stream has passed its feed-out. A run with a gap in the stream (lost frames, a lost
// instrument) or a sample beyond the transducer's range cannot be used: the program is run again (an
// attempt), never stored as good. The good attempt's samples are the test's trace; the analysis runs
// on it and the operator reviews the result.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ballbar/acquisition/interfaces.hpp"
#include "ballbar/acquisition/state_machine.hpp"
#include "ballbar/analysis/circular.hpp"

namespace ballbar::acquisition {

namespace detail {
class InstrumentLink;
}

/// One run as found in the data.
struct CircularRun {
    analysis::circular::Direction direction = analysis::circular::Direction::Ccw;
    double feed_in_end_s = 0;                   ///< device time of the feed-in's commanded end
    double lag_s = 0;                           ///< the feed-in's fitted servo lag
    std::uint64_t first_seq = 0, last_seq = 0;  ///< source seqs from the stand before the feed-in to the feed-out
};

/// One run of the part program (an attempt): good when every run was found and none had a gap.
struct CircularAttempt {
    int attempt = 1;
    bool good = false;
    std::string why;                            ///< why it cannot be used
    std::uint64_t first_seq = 0, last_seq = 0;  ///< source seqs of the attempt's samples (the trace when good)
    std::vector<CircularRun> runs;
};

class CircularSink {
  public:
    virtual ~CircularSink() = default;
    virtual void on_transition(const TransitionRecord& t) = 0;
    /// New samples, in sequence order, each exactly once.
    virtual void on_samples(std::span<const analysis::BarSample> samples) = 0;
    /// An attempt ended (good or not).
    virtual void on_attempt(const CircularAttempt& a) = 0;
    /// The instrument can measure this test (its check passed): before anything is asked of the operator.
    /// A sink may create its session here, so that a refused test leaves none.
    virtual void on_instrument_accepted(const InstrumentStatus&) {}
    /// The session changed the test to fit the instrument (CircularOptions::fit_feed_in), before its
    /// check: the part program and the stored test header are this one.
    virtual void on_test_fitted(const analysis::circular::TestSpec&) {}
};

struct CircularOptions {
    std::chrono::milliseconds read_timeout{200};
    /// Reconnect attempts (each `read_timeout` long) before the session ends interrupted.
    int max_reconnect_attempts = 600;
    /// Program runs before the session ends interrupted (resumable).
    int max_attempts = 4;
    /// Stream time allowed from telling the operator to start the program to the first feed-in, on
    /// top of the program's dwell.
    double start_grace_s = 120;
    /// The part program's stand before each feed-in (s).
    double dwell_s = 1.0;
    /// Lost frames a run may have and still be used: each hole in the stream at most `max_gap_s` of
    /// device time (or three sample periods of a slow instrument, if longer), and all of a run's holes
    /// together at most `max_lost_fraction` of its samples. The analysis works on time-stamped samples,
    /// so a run with a few scattered missing samples is measured as well as a whole one (a hole of 50 ms
    /// is 0.8 mm of path at 1000 mm/min, under half the shortest cyclic pitch searched); a longer hole
    /// voids the run.
    double max_gap_s = 0.050;
    double max_lost_fraction = 0.05;
    /// The feed-in was not chosen by the operator: lower it to what the bar's range holds at the stand
    /// (95 % of the range, in 0.05 mm steps, never below kMinFittedFeedIn_mm), telling the operator,
    /// before the instrument check. A feed-in that was chosen is checked and refused if it does not fit.
    bool fit_feed_in = false;
    /// The first attempt's number (a resumed session goes on counting).
    int first_attempt = 1;
    /// Set from a SIGINT handler: the session ends Aborted with `interrupted` set.
    const std::atomic<bool>* stop = nullptr;
};

/// The shallowest feed-in fit_feed_in chooses: below it the run finder's fall is lost in the lag.
inline constexpr double kMinFittedFeedIn_mm = 0.3;

struct CircularSummary {
    State final_state = State::Connecting;
    std::string reason;
    bool interrupted = false;  ///< ended resumable
    bool refused = false;      ///< the instrument cannot measure this test (bar, range, rate): a usage error
    int attempts = 0;
    std::size_t samples = 0;
    std::size_t duplicates_dropped = 0;
    std::size_t gaps = 0;          ///< holes in the stream (lost frames), kept or not
    std::size_t lost_samples = 0;  ///< samples those holes lost, by their sequence numbers
    std::size_t pauses = 0;
    std::optional<CircularAttempt> good;
    std::vector<analysis::circular::TraceSample> trace;  ///< the good attempt's samples
    std::optional<analysis::circular::CircularResult> result;
};

/// Why this instrument cannot measure this test ("" when it can): the bar's calibrated length against
/// the radius and the feed-in within its range, and the feed against its reading rate (naming the
/// highest usable feed).
std::string circular_instrument_mismatch(const analysis::circular::TestSpec& test, const InstrumentStatus& status);

class CircularSession {
  public:
    CircularSession(analysis::circular::TestSpec test, SampleSource& source, CircularSink& sink, Operator& op,
                    CircularOptions options = {});
    ~CircularSession();
    CircularSession(const CircularSession&) = delete;
    CircularSession& operator=(const CircularSession&) = delete;
    CircularSummary run();
    State state() const { return sm_.state(); }

  private:
    class Stop {};
    void fire(Event e, const std::string& detail = {});
    [[noreturn]] void end(Event e, const std::string& reason);
    [[noreturn]] void end_interrupted(const std::string& reason);
    void check_stop();
    void fit_feed_in();
    /// One run of the program; true when every run was captured.
    bool attempt(int number);
    double run_duration_s(std::size_t run) const;

    analysis::circular::TestSpec test_;
    SampleSource& source_;
    CircularSink& sink_;
    Operator& op_;
    CircularOptions options_;
    StateMachine sm_;
    std::unique_ptr<detail::InstrumentLink> link_;  ///< reference, stream, reconnects (instrument_link.hpp)
    InstrumentStatus status_;
    std::optional<std::uint64_t> last_seq_;
    CircularSummary summary_;
};

}  // namespace ballbar::acquisition
