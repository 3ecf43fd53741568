// SPDX-License-Identifier: MIT
// The acquisition's interfaces on real parts: the instrument driver as a SampleSource, the database as
// a SessionSink, the terminal as an Operator. Used by `ballbar measure` and `ballbar demo`.
#pragma once

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>

#include "ballbar/acquisition/interfaces.hpp"
#include "ballbar/acquisition/session.hpp"
#include "ballbar/device/instrument.hpp"
#include "ballbar/storage/sample_writer.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/workflow/gauge_source.hpp"

namespace ballbar::workflow {

/// The instrument driver over a transport that `open` (re)creates: reconnecting opens a new link.
/// Samples are renumbered into one contiguous host sequence across reconnects; a gap the driver
/// reports (kSampleAfterGap) skips one number so the acquisition sees it.
class DeviceSource : public acquisition::SampleSource {
  public:
    using Opener = std::function<std::unique_ptr<device::Transport>()>;
    explicit DeviceSource(Opener open, int sample_rate_hz = 1000);

    acquisition::InstrumentStatus connect() override;
    void set_reference() override;
    void start() override;
    void stop() override;
    acquisition::ReadStatus read(std::span<analysis::BarSample> out, std::size_t& n,
                                 std::chrono::milliseconds timeout) override;
    bool reconnect(std::chrono::milliseconds timeout) override;

    const std::optional<device::InstrumentInfo>& info() const { return info_; }
    int sample_rate_hz() const { return rate_hz_; }  ///< the rate the instrument is told to stream at
    /// Called after every identify (connect, reconnect), before anything else is asked of the instrument
    /// or the operator: records the identity with the session, checks the bar. May throw SourceError.
    std::function<void(const device::InstrumentInfo&)> on_identified;
    std::uint64_t lost_frames() const { return lost_frames_ + (inst_ ? inst_->stats().lost_frames : 0); }

  private:
    acquisition::InstrumentStatus open_and_identify();

    Opener open_;
    int rate_hz_;
    std::unique_ptr<device::Instrument> inst_;
    std::optional<device::InstrumentInfo> info_;
    std::uint64_t next_seq_ = 0;
    std::uint64_t lost_frames_ = 0;
};

/// How a use case opens the instrument at `uri`: `override` when given (an emulator in process, for tests
/// and demos), else the URI's transport; a URI that names no transport is a SourceError (the session says
/// so as a link failure).
DeviceSource::Opener device_opener(std::string uri, DeviceSource::Opener override = {});

/// Records the bar's resolution and streaming rate on the session's segments from `first_seq` (the
/// ones this connection wrote), once the instrument has identified itself; nothing otherwise.
void store_bar_resolution(storage::Store& store, std::int64_t session_id, const DeviceSource& source,
                          std::uint64_t first_seq);

/// The instrument a session measures with, as the acquisition's sample source: a digital gauge for a
/// gauge URI (sylvac:, mitutoyo-itn:, digimatic:, modbus:; docs/instruments.md), else the ball-bar's
/// driver over the URI's transport (or `override`: an emulator in process).
struct OpenedSource {
    std::unique_ptr<DeviceSource> ballbar;  ///< set for the ball-bar protocol
    std::unique_ptr<GaugeSource> gauge;     ///< set for a gauge
    acquisition::SampleSource& source() const {
        return gauge ? static_cast<acquisition::SampleSource&>(*gauge) : *ballbar;
    }
};

/// Opens nothing yet (the acquisition connects): chooses and builds the source for `uri`. A gauge is set up
/// as a bar of `calibrated_length_mm`; `override` always means the ball-bar protocol.
OpenedSource open_source(const std::string& uri, double calibrated_length_mm, DeviceSource::Opener override = {});

/// Stores a session as it happens: samples through a SampleWriter, points, the fine-grained audit
/// trail (the procedure's steps) and the results (kinds "acquisition.plan", "ssm", "orientation").
class StoreSink : public acquisition::SessionSink {
  public:
    StoreSink(storage::Store& store, std::int64_t session_id, const acquisition::Plan& plan);

    void on_transition(const acquisition::TransitionRecord& t) override;
    void on_samples(std::span<const analysis::BarSample> samples) override;
    void on_point(const acquisition::CapturedPoint& p) override;
    void on_location(const acquisition::LocationResult& r) override;
    void on_test(const acquisition::TestResult& r) override;
    /// Commits pending samples and moves the stored session to the state matching the summary's final
    /// state; a session the operator interrupted becomes `interrupted`, so `measure --resume` takes it up.
    void finish(const acquisition::SessionSummary& summary);

  private:
    /// The stored seq of a sample the source numbered `source_seq` (the source leaves a hole in its
    /// numbering at every gap and restarts at 0 in a resumed run; storage numbers gap-free and goes on
    /// from the stored samples, so a point's window is stored in storage's numbering).
    std::uint64_t stored_seq(std::uint64_t source_seq) const;

    storage::Store& store_;
    std::int64_t id_;
    const acquisition::Plan& plan_;
    storage::SampleWriter writer_;
    /// One entry per run of consecutive source seqs: where it starts in both numberings.
    struct SeqRun {
        std::uint64_t source = 0, stored = 0;
    };
    std::vector<SeqRun> runs_;
    std::uint64_t last_source_ = 0, last_stored_ = 0;
};

/// The identity an instrument reported, as the session stores it (sessions show, the report).
storage::Instrument stored_instrument(const device::InstrumentInfo& info);

/// Stores the plan with a new session (for --resume) and reads it back.
void store_plan(storage::Store& store, std::int64_t session_id, const acquisition::Plan& plan);
acquisition::Plan load_plan(storage::Store& store, std::int64_t session_id);
/// The points of a stored session, as the acquisition captured them (plan order).
std::vector<acquisition::CapturedPoint> load_points(storage::Store& store, std::int64_t session_id,
                                                    const acquisition::Plan& plan);

}  // namespace ballbar::workflow
