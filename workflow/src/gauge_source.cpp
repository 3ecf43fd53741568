// SPDX-License-Identifier: MIT
#include "ballbar/workflow/gauge_source.hpp"

#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "ballbar/storage/instrument_result.hpp"

namespace ballbar::workflow {

namespace acq = ballbar::acquisition;
namespace gg = ballbar::device::gauge;
using acq::ReadStatus;
using acq::SourceError;

GaugeSource::GaugeSource(Opener open, gg::BarOnGauge bar, gg::GaugeSampler::Clock clock)
    : open_(std::move(open)), bar_(bar), clock_(std::move(clock)) {}

const gg::SamplerStats& GaugeSource::stats() const {
    return sampler_ ? sampler_->stats() : last_stats_;
}

acq::InstrumentStatus GaugeSource::open_and_measure() {
    sampler_ = std::make_unique<gg::GaugeSampler>(open_(), bar_, clock_);
    if (zero_mm_) sampler_->set_zero_value(*zero_mm_);
    identity_ = sampler_->identify();
    uri_ = sampler_->gauge().uri();
    sampler_->measure(10);  // the actual reading rate and resolution, before any window is sized
    if (sampler_->stats().readings == 0) throw SourceError(uri_ + ": the gauge gives no readings");
    acq::InstrumentStatus s;
    std::ostringstream d;
    d << identity_->maker << " " << identity_->model;
    if (!identity_->serial.empty()) d << " serial " << identity_->serial;
    if (!identity_->firmware.empty()) d << " (" << identity_->firmware << ")";
    d << " on " << uri_ << ": " << sampler_->stats().rate_hz << " readings/s, resolution "
      << sampler_->stats().resolution_mm * 1e3 << " µm";
    s.description = d.str();
    s.battery_pct = identity_->low_battery ? 10 : 100;
    s.bar_temp_C = std::nullopt;
    s.has_thermometer = false;  // a gauge has no bar thermometer: nothing failed
    s.referenced = zero_mm_.has_value();
    s.calibrated_length_mm = bar_.calibrated_length_mm;
    s.sample_rate_hz = sampler_->stats().rate_hz;
    return s;
}

acq::InstrumentStatus GaugeSource::connect() {
    try {
        return open_and_measure();
    } catch (const device::DeviceError& e) {
        throw SourceError(e.what());
    } catch (const std::invalid_argument& e) {
        throw SourceError(e.what());
    }
}

void GaugeSource::set_reference() {
    try {
        sampler_->set_zero(5);
        zero_mm_ = sampler_->zero_mm();
    } catch (const device::DeviceError& e) {
        throw SourceError(std::string("zeroing the gauge in the calibrator: ") + e.what());
    }
}

ReadStatus GaugeSource::read(std::span<analysis::BarSample> out, std::size_t& n, std::chrono::milliseconds timeout) {
    n = 0;
    if (!sampler_ || out.empty()) return sampler_ ? ReadStatus::Timeout : ReadStatus::Disconnected;
    try {
        const auto deadline = std::chrono::steady_clock::now() + timeout;
        while (n < out.size() && n < 8) {
            if (auto s = sampler_->poll(timeout)) {
                if (s->flags & analysis::kSampleAfterGap) ++next_seq_;  // leave the hole visible
                s->flags = static_cast<std::uint16_t>(s->flags & ~analysis::kSampleAfterGap);
                s->seq = next_seq_++;
                out[n++] = *s;
            }
            if (std::chrono::steady_clock::now() >= deadline) break;
        }
    } catch (const device::DeviceError& e) {
        if (e.kind() == device::DeviceErrorKind::Disconnected || e.kind() == device::DeviceErrorKind::Io) {
            last_stats_ = sampler_->stats();
            sampler_.reset();
            return n > 0 ? ReadStatus::Ok : ReadStatus::Disconnected;
        }
        throw SourceError(e.what());
    }
    return n > 0 ? ReadStatus::Ok : ReadStatus::Timeout;
}

bool GaugeSource::reconnect(std::chrono::milliseconds timeout) {
    try {
        sampler_.reset();
        (void)open_and_measure();
        return true;
    } catch (const device::DeviceError& e) {
        sampler_.reset();
        if (e.kind() == device::DeviceErrorKind::Permission) throw SourceError(e.what());
    } catch (const std::exception&) {
        sampler_.reset();
    }
    std::this_thread::sleep_for(timeout);
    return false;
}

std::string GaugeSource::instrument_json() const {
    storage::GaugeInstrumentRecord r;
    const gg::SamplerStats& st = stats();
    if (identity_) {
        r.kind = gg::to_string(identity_->kind);
        r.maker = identity_->maker;
        r.model = identity_->model;
        if (!identity_->serial.empty()) r.serial = identity_->serial;
        if (!identity_->firmware.empty()) r.firmware = identity_->firmware;
        r.inch = identity_->inch;
        r.low_battery = identity_->low_battery;
    }
    r.uri = uri_;
    r.resolution_mm = st.resolution_mm;
    r.reading_rate_hz = st.rate_hz;
    r.target_rate_hz = bar_.target_rate_hz;
    r.calibrated_length_mm = bar_.calibrated_length_mm;
    r.sign = bar_.sign < 0 ? -1 : 1;
    r.readings = st.readings;
    r.not_ready = st.not_ready;
    r.out_of_range = st.out_of_range;
    r.timeouts = st.timeouts;
    r.invalid = st.invalid;
    r.errors = st.errors;
    return storage::gauge_instrument_to_json(r);
}

std::unique_ptr<GaugeSource> make_gauge_source(const std::string& uri, double calibrated_length_mm) {
    if (!gg::is_gauge_uri(uri)) return nullptr;
    gg::BarOnGauge bar;
    bar.calibrated_length_mm = calibrated_length_mm;
    try {
        bar = gg::bar_from_uri(uri, bar);
    } catch (const std::invalid_argument& e) {
        throw SourceError(e.what());
    }
    return std::make_unique<GaugeSource>([uri] { return gg::open_gauge(uri); }, bar);
}

void store_gauge_instrument(storage::Store& store, std::int64_t session_id, const GaugeSource& source,
                            std::uint64_t first_seq, bool keep_instrument) {
    const auto& id = source.identity();
    if (!id) return;
    if (!keep_instrument) {
        storage::Instrument in;
        in.model = id->maker + " " + id->model;
        in.serial = id->serial;
        in.firmware = id->firmware;
        in.calibrated_length_mm = source.bar().calibrated_length_mm;
        store.set_instrument(session_id, in);
    }
    store.add_result(session_id, std::string(storage::kInstrumentResultKind), source.instrument_json(), std::nullopt,
                     "ballbar gauge/1");
    const gg::SamplerStats& st = source.stats();
    if (st.resolution_mm > 0 && st.rate_hz > 0)
        store.set_segment_instrument(session_id, first_seq, st.resolution_mm, st.rate_hz);
}

}  // namespace ballbar::workflow
