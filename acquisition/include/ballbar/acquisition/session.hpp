// SPDX-License-Identifier: MIT
// Runs a plan through the state machine: instrument check, set-up, then NC programs until every
// planned point is captured: the full program first, then retry programs for exactly the points still
// missing. Each dwell is attributed to its point from the code the program writes into the bar length
// (attribution.hpp), never by counting dwells; a dwell that cannot be attributed is not stored. The
// program's own timing (nc_writer.hpp's ProgramEntry) bounds every wait. Program stops (M0) prompt the
// operator; a lost instrument is re-referenced when it is back and the points the running program did
// not deliver go to a retry program. Samples, points (with their evidence), transitions and results go
// to the sink as they happen. A session that cannot finish ends interrupted (resumable) with the list
// of its missing points.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ballbar/acquisition/attribution.hpp"
#include "ballbar/acquisition/interfaces.hpp"
#include "ballbar/acquisition/nc_writer.hpp"
#include "ballbar/acquisition/state_machine.hpp"

namespace ballbar::acquisition {

namespace detail {
class InstrumentLink;
}

struct SessionOptions {
    std::chrono::milliseconds read_timeout{200};
    /// Consecutive read timeouts while the program runs before the instrument counts as silent: the
    /// program is abandoned (its missing points go to a retry program).
    int max_silent_reads = 150;
    /// Reconnect attempts (each `read_timeout` long) before a paused session ends interrupted.
    int max_reconnect_attempts = 600;
    /// Samples between two progress reports.
    std::size_t progress_every = 100;
    /// ... or this much device time, whichever comes first: a screen's live reading at 50 Hz whatever
    /// the instrument's rate (a 1 kHz bar, a 20 readings/s gauge).
    double progress_interval_s = 0.02;
    /// Stream time allowed from telling the operator to start a program (or to press cycle start) to
    /// the program's first dwell, on top of the program's own timing.
    double start_grace_s = 120;
    /// The program's timing runs from the machine's first motion after a start or cycle start (a bar
    /// length this far from where it stood: below the smallest point-code tag), so a machine standing
    /// at a stop (cycle start pressed late, a feed hold) is not late ...
    double motion_start_mm = 0.1;
    /// ... unless it stands still this long: then the timing runs anyway.
    double max_standstill_s = 300;
    /// The slowest feed override the timing allows for (moves take up to 1/override as long).
    double slowest_feed_override = 0.5;
    /// The slowest rapid assumed for G0 moves (mm/min).
    double slowest_rapid_mm_min = 1000;
    /// Programs a session runs before it stops with its missing points (resumable).
    int max_programs = 8;
    /// Set (from a SIGINT handler, say) to stop the session: it ends Aborted with `interrupted` set at
    /// the next read or question, so the caller can keep it resumable.
    const std::atomic<bool>* stop = nullptr;
};

struct SessionSummary {
    State final_state = State::Connecting;
    std::string reason;                ///< why it ended in Aborted/Failed
    bool interrupted = false;          ///< ended resumable (Ctrl-C, or points still missing); final_state Aborted
    std::vector<std::size_t> missing;  ///< plan indices not captured when the session ended
    std::size_t samples = 0;
    std::size_t duplicates_dropped = 0;
    std::size_t gaps = 0;         ///< sequence gaps seen (samples the instrument lost)
    std::size_t recaptures = 0;   ///< dwells attributed but failing their checks
    std::size_t void_dwells = 0;  ///< dwells that could not be attributed (not stored)
    std::size_t pauses = 0;
    std::size_t programs = 0;  ///< NC programs run (the first one and the retries)
    std::vector<TestResult> tests;
};

class Session {
  public:
    Session(const Plan& plan, SampleSource& source, SessionSink& sink, Operator& op, SessionOptions options = {});
    ~Session();
    Session(const Session&) = delete;
    Session& operator=(const Session&) = delete;

    /// Points of an interrupted session (any order, each at its planned place).
    void restore(std::span<const CapturedPoint> done);
    /// Plan indices still to capture.
    std::vector<std::size_t> missing() const;

    SessionSummary run();
    State state() const { return sm_.state(); }

  private:
    class Stop {};  // unwinds run() when the session ends early
    enum class RunEnd { Complete, Ended, Lost };
    void fire(Event e, std::string detail = {});
    void end(Event e, const std::string& reason);
    void end_interrupted(const std::string& reason);
    bool stop_requested() const;
    void check_stop();
    void check_instrument();
    void set_up();
    void measure_missing();
    RunEnd run_program(const std::vector<std::size_t>& points, bool retry);
    void program_stops(const ProgramEntry& entry);
    bool decide_failed_points();
    void on_captured(const AttributionEvent& ev, std::size_t entry);
    void on_void(const AttributionEvent& ev);
    bool fetch();  // false: the instrument was lost (and is back, re-referenced)
    void stream_on();
    void compute_all();
    bool review();
    /// `start_wait_left_s`, `point_due_s`: the run loop's countdowns (Progress).
    void report_progress(std::optional<double> start_wait_left_s = std::nullopt,
                         std::optional<double> point_due_s = std::nullopt, double entry_elapsed_s = 0);
    double entry_timeout_s(const ProgramEntry& e) const;
    double entry_time_s(const ProgramEntry& e) const;

    const Plan& plan_;
    SampleSource& source_;
    SessionSink& sink_;
    Operator& op_;
    SessionOptions options_;
    StateMachine sm_;
    std::unique_ptr<detail::InstrumentLink> link_;  ///< reference, stream, reconnects (instrument_link.hpp)
    InstrumentStatus status_;
    std::vector<std::optional<CapturedPoint>> captured_;  ///< by plan index
    std::vector<int> failures_;                           ///< failed checks per point since last decision
    std::vector<std::optional<CapturedPoint>> best_failed_;
    std::vector<std::string> failure_why_;
    std::optional<AttributionSettings> attribution_settings_;
    std::optional<DwellAttributor> attributor_;
    std::optional<DwellDetector> manual_;
    std::array<analysis::BarSample, 256> buffer_{};
    std::size_t buffer_n_ = 0;
    std::optional<std::uint64_t> last_seq_;
    std::optional<std::uint64_t> first_time_us_;
    std::optional<std::uint64_t> stream_now_us_;
    int silent_reads_ = 0;
    // The program being run (for progress).
    const MeasuringProgram* program_ = nullptr;
    std::size_t cursor_ = 0;
    SessionSummary summary_;
};

}  // namespace ballbar::acquisition
