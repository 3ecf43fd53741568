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

#include "ballbar/acquisition/plan.hpp"
#include "ballbar/acquisition/state_machine.hpp"
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

struct InstrumentStatus {
    std::string description;  ///< "BB-1E EMU00001 fw 1.0.0"
    double battery_pct = 100;
    std::optional<double> bar_temp_C;  ///< empty: the sensor failed
    bool referenced = false;
    double calibrated_length_mm = 100;
    double sample_rate_hz = 1000;
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
    /// Up to out.size() samples into `out`; `n` says how many. Samples carry contiguous `seq` numbers;
    /// after a reconnect they continue the numbering (a repeat or a gap is the acquisition's to notice).
    virtual ReadStatus read(std::span<analysis::BarSample> out, std::size_t& n, std::chrono::milliseconds timeout) = 0;
    /// After Disconnected: tries to get the instrument back and streaming; false when not (yet) back.
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
    double time_s = 0;  ///< device time of the window's middle, since the session's first sample
    double bar_temp_C = 20;
    bool operator_accepted = false;  ///< failed a quality check and the operator kept it
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
    double fill = 0;  ///< 0..1 of the current averaging window
};

class Operator {
  public:
    virtual ~Operator() = default;
    /// A yes/no question; `what` identifies it for scripted answers ("setup", "reference", "accept", …).
    virtual bool confirm(std::string_view what, std::string_view prompt) = 0;
    virtual void message(std::string_view text) = 0;
    /// A point failed its checks after the automatic re-captures.
    virtual PointFailureAction point_failed(const CapturedPoint& p, std::string_view why) = 0;
    /// Manual mode: returns when the operator says the machine stands at the point.
    virtual void wait_at_point(const PlannedPoint& p) = 0;
    virtual void progress(const Progress& p) = 0;
    /// The machine must run the plan's NC program from `from_point` now: once the bar streams (cycle
    /// start), and again after the instrument came back (its dwell at the point may have passed while
    /// the bar was away) — `from_point` is then the first point not captured.
    virtual void run_program(std::size_t from_point) = 0;
};

/// Answers from the plan file; messages and progress are dropped.
class ScriptedOperator : public Operator {
  public:
    explicit ScriptedOperator(Answers answers) : answers_(std::move(answers)) {}
    bool confirm(std::string_view what, std::string_view) override {
        if (what == "setup") return answers_.confirm_setup;
        if (what == "accept") return answers_.accept_results;
        return true;
    }
    void message(std::string_view) override {}
    PointFailureAction point_failed(const CapturedPoint&, std::string_view) override {
        return answers_.on_point_failure;
    }
    void wait_at_point(const PlannedPoint&) override {}
    void progress(const Progress&) override {}
    void run_program(std::size_t) override {}

  private:
    Answers answers_;
};

}  // namespace ballbar::acquisition
