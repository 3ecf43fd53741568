// SPDX-License-Identifier: MIT
// The ISO 230-4 circular test measured as a use case (`ballbar circle measure`, `demo --test circular`,
// and the web page to come): a new session or one taken up again, the instrument at a device URI (the
// ball-bar protocol or a digital gauge), every sample, transition and run of the program stored as it
// happens, the session's stored state set as the run ends, and the stored trace analysed and its result
// stored. The front end gives the operator (the questions, the program to start) and a stop flag, and
// says what the summary means to its user (docs/circular.md).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ballbar/acquisition/circular_session.hpp"
#include "ballbar/analysis/circular.hpp"
#include "ballbar/analysis/nc_program.hpp"
#include "ballbar/device/instrument.hpp"
#include "ballbar/device/transport.hpp"
#include "ballbar/storage/sample_writer.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/storage/trace_file.hpp"

namespace ballbar::workflow {

/// Stores the circular procedure as it happens: every sample (SampleWriter), every transition (the
/// audit trail), each run of the program as a result of kind "circular.attempt" with its window of
/// stored samples; the good attempt's window is the session's trace (storage::load_trace). A new session
/// is created only once the instrument is accepted for the test (`create`), so a refused test leaves
/// none; the transitions before are kept for it.
class CircularStoreSink : public acquisition::CircularSink {
  public:
    using Create = std::function<std::int64_t()>;
    CircularStoreSink(storage::Store& store, Create create, double reference_length_mm);
    CircularStoreSink(storage::Store& store, std::int64_t id, double reference_length_mm);

    std::optional<std::int64_t> id() const { return id_; }
    /// The instrument identified: its length is the samples' reference; it is the session's instrument.
    void identified(const device::InstrumentInfo& info);
    /// Called when the session fits the test to the instrument (before on_instrument_accepted).
    std::function<void(const analysis::circular::TestSpec&)> test_fitted;

    void on_instrument_accepted(const acquisition::InstrumentStatus&) override { ensure(); }
    void on_test_fitted(const analysis::circular::TestSpec& t) override {
        if (test_fitted) test_fitted(t);
    }
    void on_transition(const acquisition::TransitionRecord& t) override;
    void on_samples(std::span<const analysis::BarSample> samples) override;
    void on_attempt(const acquisition::CircularAttempt& a) override;
    /// The session's stored state from how the run ended (nothing when no session was made).
    void finish(const acquisition::CircularSummary& sum);

  private:
    void ensure();
    std::int64_t stored(std::uint64_t source_seq) const;
    struct SeqRun {
        std::uint64_t source = 0, stored = 0;
    };
    storage::Store& store_;
    Create create_;
    std::optional<std::int64_t> id_;
    double reference_mm_;
    std::optional<storage::SampleWriter> writer_;
    std::optional<storage::Instrument> instrument_;
    std::vector<storage::ProcedureStep> pending_;
    std::vector<SeqRun> runs_;
    std::uint64_t last_source_ = 0, last_stored_ = 0;
};

/// A new, started circular session holding the test header, as `import` makes one, plus the part
/// program's dialect and dwell (a resume writes the same program).
/// `machine`: the machine tested (its machine file's geometry and name); none: stored as "circular test".
/// `tolerance_um`: G allowed (metadata "tolerance_um"), judged when the session's result is stored.
/// `machine_asset`: the registry's machine tested (`--asset`; `machine` is then its geometry).
std::int64_t create_circular_session(storage::Store& store, const analysis::circular::TestSpec& test,
                                     analysis::NcDialect dialect, double dwell_s, storage::SessionSource source,
                                     const std::string& operator_name, const std::string& notes,
                                     const analysis::MachineGeometry* machine = nullptr,
                                     std::optional<double> tolerance_um = std::nullopt,
                                     const std::string& machine_asset = {});

/// A circular session's stored trace analysed as `circle analyze SESSION` does, its result stored with it
/// (kind "circular"), with the tolerance the session was measured against (metadata "tolerance_um", if
/// any). Error (failed) naming the session when the stored trace cannot be analysed.
struct StoredCircularResult {
    analysis::circular::CircularResult result;
    storage::TraceFile trace;
    std::string payload_json;  ///< the stored result (storage/circular_result.hpp)
};
StoredCircularResult analyze_stored_circular(storage::Store& store, std::int64_t id);

/// What a circular measurement measures: a new test, or an interrupted session taken up again.
struct PreparedCircular {
    /// The session to measure into: one taken up again, or one the front end made; empty: a new one is
    /// made once the instrument is accepted for the test (a refused test leaves none).
    std::optional<std::int64_t> session;
    analysis::circular::TestSpec test;
    analysis::NcDialect dialect = analysis::NcDialect::Fanuc;
    double dwell_s = 1.0;
    int first_attempt = 1;                       ///< the number of the next run of the program
    std::optional<storage::SessionInfo> before;  ///< a resumed session as it was (its state, why it stopped)
};

/// Takes up an interrupted or failed circular session (an id or uuid prefix): its test and the program's
/// dialect and dwell as stored (`dialect` and `dwell_s` when the session stored none). Error (not found)
/// when no session matches; Error (bad input) when it is not a circular test or its state forbids going
/// on — nothing is changed then.
PreparedCircular resume_circular_session(storage::Store& store, const std::string& key,
                                         analysis::NcDialect dialect = analysis::NcDialect::Fanuc,
                                         double dwell_s = 1.0);

struct CircularMeasureOptions {
    std::string device_uri;
    std::string operator_name;
    std::string notes = "circle measure";
    /// The machine tested (`circle measure --machine FILE`): its sessions are listed and trended under it.
    std::optional<analysis::MachineGeometry> machine;
    /// The registry's machine tested (`circle measure --asset`): `machine` is its geometry.
    std::string machine_asset;
    /// G allowed, µm (the machine file's tolerances.circularity_um): stored with the session, so its
    /// result (also after a resume) and its report carry the PASS/FAIL verdict.
    std::optional<double> tolerance_um;
    /// Fit the feed-in to the bar's range (a test the operator did not shape); the program and the stored
    /// header follow it (on_test_fitted).
    bool fit_feed_in = false;
    const std::atomic<bool>* stop = nullptr;  ///< set: stop, store, stay resumable (Ctrl-C, a page's button)
    /// A new session was made (once the instrument is accepted for the test): its id and test.
    std::function<void(std::int64_t, const analysis::circular::TestSpec&)> on_session_created;
    /// The test fitted to the instrument: the program to give the operator changes with it.
    std::function<void(const analysis::circular::TestSpec&)> on_test_fitted;
    /// Opens the link to the ball-bar instead of `device_uri` (which still names the session's source): an
    /// emulator in process, for tests and demos. Not for gauges.
    std::function<std::unique_ptr<device::Transport>()> open_transport;
};

struct CircularMeasureResult {
    acquisition::CircularSummary summary;
    std::optional<std::int64_t> session_id;      ///< empty when the test was refused before a session was made
    analysis::circular::TestSpec test;           ///< as measured (fitted)
    std::optional<StoredCircularResult> stored;  ///< the analysed result of a completed session
};

/// Runs the circular procedure on the instrument at `options.device_uri` with `op` answering its
/// questions. Stores everything as it comes, sets the session's stored state from how the run ended, and
/// for a completed session analyses the stored trace and stores the result.
CircularMeasureResult measure_circular(storage::Store& store, const PreparedCircular& prepared,
                                       acquisition::Operator& op, const CircularMeasureOptions& options);

/// What a summary means as an error: nothing for a completed run; otherwise Error of the category it is
/// (interrupted: resumable, with `resume_hint`, the command that continues it, empty for a demo; refused: bad input;
/// aborted; failed), naming the session.
void throw_unless_completed(const acquisition::CircularSummary& sum, std::optional<std::int64_t> id,
                            const std::string& resume_hint);

}  // namespace ballbar::workflow
