// SPDX-License-Identifier: MIT
// A bar built on a digital gauge as the acquisition's SampleSource (docs/instruments.md): the gauge is
// polled at its rate, each reading becomes a sample; the zero is set in the calibrator; the measured
// reading rate and resolution and the gauge's identity go with the session (instrument_json()).
// The CLI's gauge paths of `monitor`, `emulate --instrument` and `demo --instrument` are in app/
// (gauge_commands.cpp, gauge_demo.cpp).
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "ballbar/acquisition/interfaces.hpp"
#include "ballbar/device/gauge.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::workflow {

class GaugeSource : public acquisition::SampleSource {
  public:
    using Opener = std::function<std::unique_ptr<device::gauge::Gauge>()>;
    GaugeSource(Opener open, device::gauge::BarOnGauge bar, device::gauge::GaugeSampler::Clock clock = {});

    acquisition::InstrumentStatus connect() override;
    void set_reference() override;
    void start() override {}
    /// A gauge is polled: it reads only while read() asks it, so there is nothing to stop.
    void stop() override {}
    acquisition::ReadStatus read(std::span<analysis::BarSample> out, std::size_t& n,
                                 std::chrono::milliseconds timeout) override;
    bool reconnect(std::chrono::milliseconds timeout) override;

    /// Identity, measured resolution and reading rate, bar set-up and reading statistics, as JSON.
    std::string instrument_json() const;
    const std::optional<device::gauge::Identity>& identity() const { return identity_; }
    const device::gauge::SamplerStats& stats() const;
    const device::gauge::BarOnGauge& bar() const { return bar_; }

  private:
    acquisition::InstrumentStatus open_and_measure();

    Opener open_;
    device::gauge::BarOnGauge bar_;
    device::gauge::GaugeSampler::Clock clock_;
    std::unique_ptr<device::gauge::GaugeSampler> sampler_;
    std::optional<device::gauge::Identity> identity_;
    std::optional<double> zero_mm_;  ///< kept across reconnects: the gauge's origin is mechanical
    std::string uri_;
    std::uint64_t next_seq_ = 0;
    device::gauge::SamplerStats last_stats_;
};

/// For `measure --device URI`: a GaugeSource on a bar of `calibrated_length_mm` (the URI's sign= and
/// rate= applied), or null when `uri` is not a gauge's.
std::unique_ptr<GaugeSource> make_gauge_source(const std::string& uri, double calibrated_length_mm);

/// After a run on a gauge: its identity as the session's instrument (unless `keep_instrument`), its
/// metadata as the result of kind `instrument`, and its resolution and measured reading rate on the
/// sample segments from `first_seq` on (every sample of the run: Store::segment_of). Nothing before the
/// gauge was identified.
void store_gauge_instrument(storage::Store& store, std::int64_t session_id, const GaugeSource& source,
                            std::uint64_t first_seq, bool keep_instrument = false);

}  // namespace ballbar::workflow
