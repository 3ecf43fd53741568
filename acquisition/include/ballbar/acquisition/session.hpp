// SPDX-License-Identifier: MIT
// Runs a plan through the state machine: instrument check, set-up, then for each test step 1 and
// step 2 (dwell capture of every point), SSM and the orientation model, review. Samples, points,
// transitions and results go to the sink as they happen. A lost instrument pauses the session; it
// continues at the same point when the instrument is back. Given the points of an interrupted
// session, it continues after the last completed one.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ballbar/acquisition/dwell.hpp"
#include "ballbar/acquisition/interfaces.hpp"
#include "ballbar/acquisition/state_machine.hpp"

namespace ballbar::acquisition {

struct SessionOptions {
    std::chrono::milliseconds read_timeout{200};
    /// Consecutive read timeouts before the instrument counts as silent (Fail).
    int max_silent_reads = 150;
    /// Reconnect attempts (each `read_timeout` long) before a paused session fails.
    int max_reconnect_attempts = 600;
    /// Samples between two progress reports.
    std::size_t progress_every = 100;
    /// Set (from a SIGINT handler, say) to stop the session: it ends Aborted at the next read of the
    /// instrument or the next thing that fails because of the signal, with `interrupted` set, so the
    /// caller can keep it resumable. Must be lock-free (it is read, never written, here).
    const std::atomic<bool>* stop = nullptr;
};

struct SessionSummary {
    State final_state = State::Connecting;
    std::string reason;        ///< why it ended in Aborted/Failed
    bool interrupted = false;  ///< ended because SessionOptions::stop was set (final_state Aborted)
    std::size_t samples = 0;
    std::size_t duplicates_dropped = 0;
    std::size_t gaps = 0;  ///< sequence gaps seen (samples the instrument lost)
    std::size_t recaptures = 0;
    std::size_t pauses = 0;
    std::vector<TestResult> tests;
};

class Session {
  public:
    Session(const Plan& plan, SampleSource& source, SessionSink& sink, Operator& op, SessionOptions options = {});

    /// Points of an interrupted session, in plan order from its first point (resume).
    void restore(std::span<const CapturedPoint> done);
    /// Index of the first point still to capture.
    std::size_t next_point() const { return captured_.size(); }

    SessionSummary run();
    State state() const { return sm_.state(); }

  private:
    class Stop {};  // unwinds run() when the session ends early
    void fire(Event e, std::string detail = {});
    void end(Event e, const std::string& reason);
    bool stop_requested() const;  // SessionOptions::stop is set
    void check_stop();            // ends the session (interrupted) once it is
    void check_instrument();
    void set_up();
    void measure_test(int test);
    void capture_step(int test, int step);
    void capture_point(const PlannedPoint& planned, bool first_of_step);
    std::optional<WindowStats> wait_for_window(const PlannedPoint& planned, bool first_of_step);
    void fetch();
    void pause();
    void compute(int test);
    void report_progress(const PlannedPoint& planned);

    const Plan& plan_;
    SampleSource& source_;
    SessionSink& sink_;
    Operator& op_;
    SessionOptions options_;
    StateMachine sm_;
    InstrumentStatus status_;
    std::vector<CapturedPoint> captured_;
    std::vector<LocationResult> locations_;
    std::array<analysis::BarSample, 256> buffer_{};
    std::size_t buffer_n_ = 0, buffer_pos_ = 0;
    std::optional<std::uint64_t> last_seq_;
    std::optional<std::uint64_t> first_time_us_;
    std::optional<DwellDetector> detector_;
    int silent_reads_ = 0;
    bool broken_ = false;  ///< a gap or a pause since the last fetch
    SessionSummary summary_;
};

}  // namespace ballbar::acquisition
