// SPDX-License-Identifier: MIT
// What the acquisition consumes and produces, as interfaces app/ implements (device → SampleSource,
// storage → SessionSink, terminal → Operator), so the procedure is testable with neither.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/acquisition/nc_writer.hpp"
#include "ballbar/acquisition/plan.hpp"
#include "ballbar/acquisition/state_machine.hpp"
#include "ballbar/analysis/nc_program.hpp"
#include "ballbar/analysis/orientation.hpp"
#include "ballbar/analysis/sample.hpp"
#include "ballbar/analysis/ssm.hpp"

namespace ballbar::acquisition {

/// The instrument cannot be used (not found, refused, gone for good). Disconnects are not errors: they
/// are ReadStatus::Disconnected.
class SourceError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// The instrument answered, but it is not one this session can use (another bar length than the
/// plan's): the session fails and says how to fix it. Any other SourceError while opening (no answer,
/// busy, absent) leaves the session interrupted and resumable.
class InstrumentUnfit : public SourceError {
  public:
    using SourceError::SourceError;
};

struct InstrumentStatus {
    std::string description;  ///< "BB-1E EMU00001 fw 1.0.0"
    double battery_pct = 100;
    std::optional<double> bar_temp_C;  ///< empty: no bar temperature (see has_thermometer)
    /// false: an instrument without a bar thermometer (a digital gauge): it reports no bar temperature
    /// and nothing has failed. true with bar_temp_C empty: the bar's sensor failed.
    bool has_thermometer = true;
    bool referenced = false;
    double calibrated_length_mm = 100;
    double sample_rate_hz = 1000;
    std::optional<double> range_mm;  ///< the transducer's range (±), when the instrument says it
};

enum class ReadStatus { Ok, Timeout, Disconnected };

class SampleSource {
  public:
    virtual ~SampleSource() = default;
    /// Opens the instrument and reads its status. Throws SourceError.
    virtual InstrumentStatus connect() = 0;
    /// Sets the reference (zero) with the bar in its calibrator. Throws SourceError.
    virtual void set_reference() = 0;
    /// Starts streaming samples. Throws SourceError.
    virtual void start() = 0;
    /// Stops streaming (before the operator is asked something, so a long wait loses nothing and
    /// overruns nothing). Throws SourceError.
    virtual void stop() = 0;
    /// Up to out.size() samples into `out`; `n` says how many. Samples carry contiguous `seq` numbers;
    /// after a reconnect they continue the numbering (a repeat or a gap is the acquisition's to notice).
    virtual ReadStatus read(std::span<analysis::BarSample> out, std::size_t& n, std::chrono::milliseconds timeout) = 0;
    /// After Disconnected: tries to get the instrument back (identified, not streaming: the session
    /// re-references it first); false when not (yet) back.
    virtual bool reconnect(std::chrono::milliseconds timeout) = 0;
};

/// One averaged point, with its planned place.
struct CapturedPoint {
    PlannedPoint planned;
    double measured_mm = 0;
    double std_mm = 0;
    double drift_mm = 0;
    std::size_t n = 0;
    std::uint64_t first_seq = 0, last_seq = 0;
    double time_s = 0;                 ///< device time of the window's middle, since the session's first sample
    std::optional<double> bar_temp_C;  ///< mean over the window; empty: no sample had a bar temperature
    bool operator_accepted = false;    ///< failed a quality check and the operator kept it
    /// Why this dwell is this point: the code read from the bar and the window's time (attribution.hpp).
    std::string evidence;
};

struct TransitionRecord {
    State from = State::Connecting;
    State to = State::Connecting;
    Event event = Event::Connected;
    std::string detail;
};

/// SSM result of one step of one test.
struct LocationResult {
    int test = 0;
    int step = 1;
    analysis::Vec3 datum_mm = analysis::Vec3::Zero();
    analysis::SsmResult ssm;
    analysis::Vec3 dV_mm = analysis::Vec3::Zero();  ///< the seed's ΔV (sign of the moving element's error)
};

/// Orientation errors of one test.
struct TestResult {
    int test = 0;
    TestKind kind = TestKind::BothAxes;
    analysis::Vec3 dV1_mm = analysis::Vec3::Zero(), dV2_mm = analysis::Vec3::Zero();
    /// Standard uncertainty of each ΔV component (SSM); zero when not known.
    analysis::Vec3 dV1_std_mm = analysis::Vec3::Zero(), dV2_std_mm = analysis::Vec3::Zero();
    analysis::OrientationSolution orientation;
    /// Standard uncertainty of orientation.exact, propagated to first order from the covariances of
    /// ΔV1 and ΔV2; empty without them or at a singular pose.
    std::optional<analysis::OrientationErrors> std_rad;
};

class SessionSink {
  public:
    virtual ~SessionSink() = default;
    virtual void on_transition(const TransitionRecord& t) = 0;
    /// New samples, in sequence order, each exactly once.
    virtual void on_samples(std::span<const analysis::BarSample> samples) = 0;
    virtual void on_point(const CapturedPoint& p) = 0;
    virtual void on_location(const LocationResult& r) = 0;
    virtual void on_test(const TestResult& r) = 0;
};

/// Live state for the operator's screen.
struct Progress {
    State state = State::Connecting;
    int test = 0, step = 1, point = 0;
    std::size_t done = 0, total = 0;  ///< points
    double live_mm = 0;               ///< latest bar length
    double expected_mm = 0;
    double fill = 0;         ///< 0..1 of the current averaging window
    double time_left_s = 0;  ///< the running program's remaining time at 100 % feed
    /// The machine has not moved since the (cycle) start: seconds of standstill left before the program's
    /// timing runs anyway (a countdown to the start timeout).
    std::optional<double> start_wait_left_s;
    /// The program runs: seconds of stream time left before the point due now counts as missing.
    std::optional<double> point_due_s;
    /// Circular test: the angle the tool is at on the circle (degrees, the test's plane), once the
    /// run's feed-in is found in the data.
    std::optional<double> angle_deg;
    double range_mm = 0;        ///< the transducer's range (±) around its zero; 0 when the instrument does not say
    bool out_of_range = false;  ///< the latest sample is beyond the transducer's range
};

/// A choice among named options ("retry", "accept", "abort"); the answer is the option's index.
struct Choice {
    std::string what;    ///< identifies the question for scripted answers ("missing", "review", …)
    std::string prompt;  ///< the question, with everything the operator needs to decide
    std::vector<std::string> options;
    std::size_t default_option = 0;  ///< what a scripted run answers unless its plan says otherwise
};

class Operator {
  public:
    virtual ~Operator() = default;
    /// A yes/no question; `what` identifies it for scripted answers ("setup", "reference", …).
    virtual bool confirm(std::string_view what, std::string_view prompt) = 0;
    /// One of several options; returns its index.
    virtual std::size_t choose(const Choice& choice) = 0;
    virtual void message(std::string_view text) = 0;
    /// A point failed its checks on every attempt (retry, accept or abort).
    virtual PointFailureAction point_failed(const CapturedPoint& p, std::string_view why) = 0;
    /// Manual mode: returns when the operator says the machine stands at the point.
    virtual void wait_at_point(const PlannedPoint& p) = 0;
    virtual void progress(const Progress& p) = 0;
    /// The machine must run `program` (the points `points` of the plan, in that order) now: the
    /// operator loads it and presses cycle start. `retry` when it is a program for missing points.
    virtual void run_program(const analysis::NcProgram& program, std::span<const std::size_t> points, bool retry) = 0;
    /// The program stops (M0) for the operator: `stop.what` says what to do there; returns once the
    /// operator did it and pressed cycle start.
    virtual void program_stop(const ProgramStop& stop) = 0;
    /// A point was captured (attributed and within its checks) and stored.
    virtual void point_captured(const CapturedPoint&) {}
    /// A continuous test (the circular test): the machine must run its part program now, from its
    /// start (`retry`: again, after a run that could not be used). `what` says which program and why.
    virtual void run_part_program(std::string_view what, bool /*retry*/) { message(what); }
    /// The instrument stopped answering: the procedure waits for it at most `timeout_s` (then it stops,
    /// resumable). A screen shows what to do and counts down; the message() before says it in words.
    virtual void instrument_lost(double /*timeout_s*/) {}
    /// While it is lost, at each attempt to reach it (about every read timeout): the seconds left before
    /// the session stops (resumable). A screen's countdown.
    virtual void instrument_waiting(double /*seconds_left*/) {}
    /// The instrument answers again (it is re-referenced before the procedure goes on).
    virtual void instrument_back() {}
};

/// Answers from the plan file; messages and progress are dropped.
class ScriptedOperator : public Operator {
  public:
    explicit ScriptedOperator(Answers answers) : answers_(std::move(answers)) {}
    bool confirm(std::string_view what, std::string_view) override {
        if (what == "setup") return answers_.confirm_setup;
        return true;
    }
    std::size_t choose(const Choice& c) override {
        if (c.what == "review") {
            for (std::size_t i = 0; i < c.options.size(); ++i)
                if (c.options[i] == (answers_.accept_results ? "accept" : "abort")) return i;
        }
        return c.default_option;
    }
    void message(std::string_view) override {}
    PointFailureAction point_failed(const CapturedPoint&, std::string_view) override {
        return answers_.on_point_failure;
    }
    void wait_at_point(const PlannedPoint&) override {}
    void progress(const Progress&) override {}
    void run_program(const analysis::NcProgram&, std::span<const std::size_t>, bool) override {}
    void program_stop(const ProgramStop&) override {}

  protected:
    Answers answers_;
};

}  // namespace ballbar::acquisition
