// SPDX-License-Identifier: MIT
#include "ballbar/workflow/session_io.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "ballbar/acquisition/nc_writer.hpp"
#include "ballbar/acquisition/result_codec.hpp"
#include "ballbar/device/gauge.hpp"
#include "ballbar/device/uri.hpp"

namespace ballbar::workflow {

using acquisition::ReadStatus;
using acquisition::SourceError;
using nlohmann::json;
namespace acq = ballbar::acquisition;

// ---- DeviceSource ----------------------------------------------------------------------------------

DeviceSource::DeviceSource(Opener open, int sample_rate_hz) : open_(std::move(open)), rate_hz_(sample_rate_hz) {}

acq::InstrumentStatus DeviceSource::open_and_identify() {
    inst_ = std::make_unique<device::Instrument>(open_());
    const device::InstrumentInfo info = inst_->identify();
    if (info_ && (info.model != info_->model || info.serial != info_->serial ||
                  info.calibrated_length_mm != info_->calibrated_length_mm)) {
        // After a loss, another instrument answers where the session's was (a port name reused after a
        // replug, another bar plugged in): it is not the session's instrument, so the session's is not
        // back (reconnect() says so; connect() is the first identify and takes any).
        inst_.reset();
        return {};
    }
    info_ = info;
    if (on_identified) on_identified(*info_);
    device::InstrumentStatus st = inst_->status();
    if (st.streaming) {
        // A host that died without stopping the stream (kill -9 of `measure`, a pulled cable) left it
        // running: the instrument refuses Configure while it streams, so take over as `monitor` does.
        inst_->stop_streaming();
        std::array<analysis::BarSample, 256> stale;  // the other host's samples: not this session's
        while (inst_->read_samples(stale) > 0) {
        }
        st = inst_->status();
    }
    acq::InstrumentStatus s;
    s.description =
        info_->model + " " + info_->serial + " (firmware " + info_->firmware + ") on " + inst_->transport().uri();
    s.battery_pct = st.battery_pct;
    if (!(st.error_flags & device::protocol::kStatusTempSensorFault)) s.bar_temp_C = st.bar_temp_C;
    s.referenced = st.referenced;
    s.calibrated_length_mm = info_->calibrated_length_mm;
    s.sample_rate_hz = rate_hz_;
    s.range_mm = info_->range_mm;
    return s;
}

acq::InstrumentStatus DeviceSource::connect() {
    try {
        acq::InstrumentStatus s = open_and_identify();
        if (!inst_) throw SourceError("another instrument answers than " + info_->model + " " + info_->serial);
        inst_->configure(rate_hz_, 1);
        return s;
    } catch (const device::DeviceError& e) {
        // Nothing answered the ball-bar protocol on a serial port: a gauge there is what the operator meant.
        if (e.kind() == device::DeviceErrorKind::Timeout && inst_) {
            const std::string uri = inst_->transport().uri();
            inst_.reset();
            throw SourceError(e.what() + device::gauge::serial_gauge_hint(uri));
        }
        throw SourceError(e.what());
    }
}

void DeviceSource::set_reference() {
    try {
        inst_->set_reference();
    } catch (const device::DeviceError& e) {
        throw SourceError(e.what());
    }
}

void DeviceSource::start() {
    if (!inst_) throw SourceError("the instrument is not connected");
    try {
        inst_->start_streaming();
    } catch (const device::DeviceError& e) {
        if (e.kind() == device::DeviceErrorKind::Disconnected) {
            lost_frames_ += inst_->stats().lost_frames;
            inst_.reset();  // the next read reports the disconnect
            return;
        }
        throw SourceError(e.what());
    }
}

void DeviceSource::stop() {
    if (!inst_) return;
    try {
        inst_->stop_streaming();
    } catch (const device::DeviceError& e) {
        if (e.kind() == device::DeviceErrorKind::Disconnected || e.kind() == device::DeviceErrorKind::Timeout) {
            lost_frames_ += inst_->stats().lost_frames;
            inst_.reset();  // the next read reports the disconnect
            return;
        }
        throw SourceError(e.what());
    }
}

ReadStatus DeviceSource::read(std::span<analysis::BarSample> out, std::size_t& n, std::chrono::milliseconds timeout) {
    n = 0;
    if (!inst_) return ReadStatus::Disconnected;
    try {
        if (inst_->queue().size() == 0) inst_->poll(timeout);
        n = inst_->read_samples(out);
    } catch (const device::DeviceError& e) {
        if (e.kind() == device::DeviceErrorKind::Disconnected) {
            lost_frames_ += inst_->stats().lost_frames;
            inst_.reset();
            return ReadStatus::Disconnected;
        }
        if (e.kind() == device::DeviceErrorKind::Timeout) return ReadStatus::Timeout;
        throw SourceError(e.what());
    }
    for (std::size_t i = 0; i < n; ++i) {
        analysis::BarSample& s = out[i];
        if (s.flags & device::kSampleAfterGap) ++next_seq_;  // leave the hole visible
        s.flags = static_cast<std::uint16_t>(s.flags & ~device::kSampleAfterGap);
        s.seq = next_seq_++;
    }
    return n > 0 ? ReadStatus::Ok : ReadStatus::Timeout;
}

bool DeviceSource::reconnect(std::chrono::milliseconds timeout) {
    try {
        inst_.reset();
        const acq::InstrumentStatus s = open_and_identify();
        (void)s;
        if (!inst_) {  // another instrument answered
            std::this_thread::sleep_for(timeout);
            return false;
        }
        inst_->configure(rate_hz_, 1);
        return true;  // not streaming: the session re-references the instrument first
    } catch (const device::DeviceError& e) {
        inst_.reset();
        if (e.kind() == device::DeviceErrorKind::Permission) throw SourceError(e.what());
        std::this_thread::sleep_for(timeout);
        return false;
    } catch (const std::invalid_argument&) {
        std::this_thread::sleep_for(timeout);
        return false;
    }
}

// ---- StoreSink -------------------------------------------------------------------------------------

StoreSink::StoreSink(storage::Store& store, std::int64_t session_id, const acq::Plan& plan)
    : store_(store), id_(session_id), plan_(plan), writer_(store, session_id) {}

void StoreSink::on_transition(const acq::TransitionRecord& t) {
    store_.add_procedure_step(id_, {std::string(acq::to_string(t.from)),
                                    std::string(acq::to_string(t.to)),
                                    std::string(acq::to_string(t.event)),
                                    t.detail,
                                    {}});
}

void StoreSink::on_samples(std::span<const analysis::BarSample> samples) {
    for (const auto& s : samples) {
        const std::uint64_t stored = writer_.append(s);
        if (runs_.empty() || s.seq != last_source_ + 1 || stored != last_stored_ + 1) runs_.push_back({s.seq, stored});
        last_source_ = s.seq;
        last_stored_ = stored;
    }
}

std::uint64_t StoreSink::stored_seq(std::uint64_t source_seq) const {
    // The last run starting at or before source_seq (the session passes samples in increasing seq).
    auto it = std::upper_bound(runs_.begin(), runs_.end(), source_seq,
                               [](std::uint64_t q, const SeqRun& r) { return q < r.source; });
    if (it == runs_.begin()) return source_seq;  // not a sample this sink stored
    --it;
    return it->stored + (source_seq - it->source);
}

void StoreSink::on_point(const acq::CapturedPoint& p) {
    writer_.flush();  // the point's window is stored before the point
    storage::PointRecord r;
    r.reading.pose = p.planned.pose;
    r.reading.socket_mm = p.planned.socket_mm;
    r.reading.measured_mm = p.measured_mm;
    r.reading.time_s = p.time_s;
    r.reading.bar_temp_C = p.bar_temp_C;
    r.reading.location = 2 * p.planned.test + (p.planned.step - 1);
    r.reading.point = p.planned.point;
    r.reading.step = p.planned.step;
    r.reading.n = static_cast<int>(p.n);
    r.reading.std_mm = p.std_mm;
    r.nominal_mm = p.planned.nominal_mm;
    r.first_seq = stored_seq(p.first_seq);
    r.last_seq = stored_seq(p.last_seq);
    store_.add_point(id_, r);
}

void StoreSink::on_location(const acq::LocationResult& r) {
    store_.add_result(id_, std::string(acq::kSsmResultKind), acq::location_to_json(r), std::nullopt,
                      "ballbar acquisition/1");
}

void StoreSink::on_test(const acq::TestResult& r) {
    store_.add_result(id_, std::string(acq::kOrientationResultKind), acq::test_to_json(r), std::nullopt,
                      "ballbar acquisition/1");
}

void StoreSink::finish(const acq::SessionSummary& summary) {
    writer_.flush();
    const std::string& reason = summary.reason;
    if (summary.interrupted) {
        store_.transition(id_, storage::SessionState::interrupted, "interrupted: " + reason);
        return;
    }
    switch (summary.final_state) {
        case acq::State::Done:
            store_.finish_session(id_);
            break;
        case acq::State::Aborted:
            store_.abort_session(id_, reason.empty() ? "abort" : "abort: " + reason);
            break;
        default:
            store_.fail_session(id_, "fail: " + reason);
            break;
    }
}

void store_bar_resolution(storage::Store& store, std::int64_t session_id, const DeviceSource& source,
                          std::uint64_t first_seq) {
    // Discovery calls nothing below the instrument's resolution structure (docs/discovery.md).
    if (source.info() && source.info()->resolution_um > 0)
        store.set_segment_instrument(session_id, first_seq, source.info()->resolution_um * 1e-3,
                                     source.sample_rate_hz());
}

storage::Instrument stored_instrument(const device::InstrumentInfo& info) {
    storage::Instrument in;
    in.model = info.model;
    in.serial = info.serial;
    in.firmware = info.firmware;
    in.calibrated_length_mm = info.calibrated_length_mm;
    in.calibration_date = info.calibration_date;
    return in;
}

void store_plan(storage::Store& store, std::int64_t session_id, const acq::Plan& plan) {
    store.add_result(session_id, std::string(acq::kPlanResultKind), acq::plan_to_json(plan), std::nullopt,
                     "ballbar acquisition/1");
}

acq::Plan load_plan(storage::Store& store, std::int64_t session_id) {
    for (const auto& r : store.results(session_id))
        if (r.kind == acq::kPlanResultKind) return acq::plan_from_json(r.payload_json);
    throw acq::PlanError("session " + std::to_string(session_id) +
                         " has no stored plan: it was not measured by ballbar measure");
}

std::vector<acq::CapturedPoint> load_points(storage::Store& store, std::int64_t session_id, const acq::Plan& plan) {
    std::vector<acq::CapturedPoint> out;
    std::vector<std::size_t> at(plan.points.size(), plan.points.size());
    for (const auto& r : store.points(session_id)) {
        // Points are stored where their code put them (any order): find each one's planned place.
        const int location = r.reading.location;
        const int test = location / 2, step = location % 2 + 1;
        if (test < 0 || test >= plan.test_count() || r.reading.point < 0 || r.reading.point >= plan.points_per_step)
            throw acq::PlanError("stored point (location " + std::to_string(location) + ", point " +
                                 std::to_string(r.reading.point) + ") is not in the session's plan");
        const std::size_t i = plan.index(test, step, r.reading.point);
        acq::CapturedPoint c;
        c.planned = plan.points[i];
        c.measured_mm = r.reading.measured_mm;
        c.std_mm = r.reading.std_mm.value_or(0);
        c.n = static_cast<std::size_t>(r.reading.n);
        c.first_seq = r.first_seq.value_or(0);
        c.last_seq = r.last_seq.value_or(0);
        c.time_s = r.reading.time_s;
        c.bar_temp_C = r.reading.bar_temp_C;
        if (at[i] < out.size()) {
            out[at[i]] = c;  // measured again (rejected results): the latest counts
        } else {
            at[i] = out.size();
            out.push_back(c);
        }
    }
    return out;
}

OpenedSource open_source(const std::string& uri, double calibrated_length_mm, DeviceSource::Opener override) {
    OpenedSource out;
    if (!override) out.gauge = make_gauge_source(uri, calibrated_length_mm);
    if (!out.gauge) out.ballbar = std::make_unique<DeviceSource>(device_opener(uri, std::move(override)));
    return out;
}

DeviceSource::Opener device_opener(std::string uri, DeviceSource::Opener override) {
    return [uri = std::move(uri), open = std::move(override)]() -> std::unique_ptr<device::Transport> {
        if (open) return open();
        try {
            return device::open_transport(uri);
        } catch (const std::invalid_argument& e) {
            throw acquisition::SourceError(e.what());
        }
    };
}

}  // namespace ballbar::workflow
