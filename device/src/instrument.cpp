// SPDX-License-Identifier: MIT
#include "ballbar/device/instrument.hpp"

#include <bit>
#include <cstring>

namespace ballbar::device {

namespace p = protocol;
using namespace std::chrono;

// ---- SampleQueue ----

SampleQueue::SampleQueue(std::size_t capacity)
    : ring_(std::bit_ceil(std::max<std::size_t>(capacity, 2))), mask_(ring_.size() - 1) {}

bool SampleQueue::push(const analysis::BarSample& s) {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail - head_.load(std::memory_order_acquire) > mask_) return false;
    ring_[tail & mask_] = s;
    tail_.store(tail + 1, std::memory_order_release);
    return true;
}

std::size_t SampleQueue::pop(std::span<analysis::BarSample> out) {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    const std::size_t n = std::min(out.size(), tail_.load(std::memory_order_acquire) - head);
    for (std::size_t i = 0; i < n; ++i) out[i] = ring_[(head + i) & mask_];
    head_.store(head + n, std::memory_order_release);
    return n;
}

std::size_t SampleQueue::size() const {
    return tail_.load(std::memory_order_acquire) - head_.load(std::memory_order_acquire);
}

// ---- Instrument ----

Instrument::Instrument(std::unique_ptr<Transport> transport, InstrumentOptions options)
    : transport_(std::move(transport)), options_(options), queue_(options.queue_capacity) {
    if (!transport_) throw std::invalid_argument("Instrument needs a transport");
}

void Instrument::protocol_error(const std::string& what) const {
    throw DeviceError(DeviceErrorKind::Protocol, transport_->uri() + ": " + what);
}

void Instrument::on_stream(const p::FrameView& frame) {
    // Before StartReply the new stream begins at 0; anything before that is left over from an earlier
    // session (a host that went away without Stop). Once it has begun, replays and gaps count as below.
    if (!streaming_ && (!start_pending_ || (!have_stream_frame_ && frame.seq != expected_stream_seq_))) {
        ++stats_.stale_frames;
        return;
    }
    if (!p::parse_stream(frame.body, frame_)) {
        ++stats_.invalid_frames;
        gap_pending_ = true;
        return;
    }
    // A sequence number in the half of the counter behind the expected one is an old frame (a replay, a
    // late duplicate) unless the device clock moved on (then > 32 768 frames were lost and it wrapped).
    const auto behind = static_cast<std::uint16_t>(expected_stream_seq_ - 1u - frame.seq);
    if (have_stream_frame_ && frame.seq != expected_stream_seq_ && behind < 0x8000u &&
        frame_.t0_us <= last_stream_t0_us_) {
        ++stats_.replayed_frames;
        return;
    }
    if (frame.seq != expected_stream_seq_) {
        stats_.lost_frames += static_cast<std::uint16_t>(frame.seq - expected_stream_seq_);
        ++stats_.gaps;
        gap_pending_ = true;
    }
    expected_stream_seq_ = static_cast<std::uint16_t>(frame.seq + 1);
    have_stream_frame_ = true;
    last_stream_t0_us_ = frame_.t0_us;
    ++stats_.frames;
    const float temp = static_cast<float>(frame_.bar_temp_cC) * 0.01f;
    const std::int32_t step_nm = info_ ? static_cast<std::int32_t>(info_->resolution_um * 1000.0 + 0.5) : 100;
    for (std::size_t i = 0; i < frame_.count; ++i) {
        analysis::BarSample s;
        s.device_time_us = frame_.t0_us + (static_cast<std::uint64_t>(frame_.period_ns) * i) / 1000;
        s.displacement_nm = frame_.samples[i].displacement * step_nm;
        s.flags = frame_.samples[i].flags;
        s.bar_temp_C = temp;
        if (gap_pending_) s.flags = static_cast<std::uint16_t>(s.flags | kSampleAfterGap);
        s.seq = host_seq_;
        if (queue_.push(s)) {
            ++host_seq_;
            ++stats_.samples;
            gap_pending_ = false;
        } else {
            ++stats_.queue_drops;
            gap_pending_ = true;
        }
    }
}

void Instrument::on_frame(const p::FrameView& frame) {
    if (frame.version != p::kVersion) {
        // Its type and body may mean anything: skip it. A stream frame it replaced shows up as a gap in
        // the sequence numbers; a request answered only in this version fails in request() naming it.
        ++stats_.unknown_version_frames;
        stats_.unknown_version = frame.version;
        return;
    }
    if (frame.type == p::MsgType::Stream) return on_stream(frame);
    if (waiting_seq_ && frame.seq == *waiting_seq_ && !reply_) {
        Reply r{frame.type, {}, frame.body.size()};
        std::memcpy(r.body.data(), frame.body.data(), frame.body.size());
        reply_ = r;
        return;
    }
    ++stats_.stale_replies;  // late answers to timed-out attempts, heartbeat replies
}

std::size_t Instrument::pump(milliseconds timeout) {
    std::size_t n = 0;
    try {
        n = transport_->read(rx_, timeout);
    } catch (const DeviceError& e) {
        if (e.kind() == DeviceErrorKind::Disconnected) {
            streaming_ = false;
            decoder_.reset();
        }
        throw;
    }
    std::span<const std::uint8_t> in{rx_.data(), n};
    while (!in.empty()) {
        const auto r = decoder_.next(in);
        if (r.status == p::DecodeStatus::Frame) {
            on_frame(r.frame);
        } else if (r.status == p::DecodeStatus::Invalid) {
            ++stats_.invalid_frames;
            if (streaming_) gap_pending_ = true;
        }
    }
    return n;
}

std::size_t Instrument::poll(milliseconds timeout) {
    if (streaming_ && steady_clock::now() - last_heartbeat_ >= options_.heartbeat_interval) {
        p::FrameBuffer buf{};
        const auto n = p::encode_heartbeat(++heartbeat_token_, next_seq_++, buf);
        transport_->write({buf.data(), n}, options_.reply_timeout);
        last_heartbeat_ = steady_clock::now();
    }
    const auto before = stats_.samples;
    pump(timeout);
    return static_cast<std::size_t>(stats_.samples - before);
}

Instrument::Reply Instrument::request(p::MsgType type, std::span<const std::uint8_t> body) {
    const std::uint64_t foreign_before = stats_.unknown_version_frames;
    for (int attempt = 0; attempt < options_.attempts; ++attempt) {
        const std::uint16_t seq = next_seq_++;
        p::FrameBuffer buf{};
        const auto n = p::encode_frame(type, seq, body, buf);
        if (type == p::MsgType::Start) {
            // Stream frames may overtake a slow StartReply: count from 0 from now on.
            expected_stream_seq_ = 0;
            have_stream_frame_ = false;
            gap_pending_ = false;
            start_pending_ = true;
        }
        transport_->write({buf.data(), n}, options_.reply_timeout);
        waiting_seq_ = seq;
        reply_.reset();
        auto remaining = duration_cast<microseconds>(options_.reply_timeout);
        while (!reply_ && remaining.count() > 0) {
            const auto t0 = steady_clock::now();
            // A read that gives nothing has used its whole timeout (in the transport's own clock, which
            // is simulated time on an emulator pipe); otherwise count the wall time it took.
            if (pump(ceil<milliseconds>(remaining)) == 0) break;
            remaining -= duration_cast<microseconds>(steady_clock::now() - t0);
        }
        waiting_seq_.reset();
        start_pending_ = false;
        if (!reply_) continue;
        Reply r = *reply_;
        reply_.reset();
        if (r.type == p::MsgType::Error) {
            const auto err = p::parse_error(r.span());
            const std::string code = err ? std::string(p::to_string(err->code)) : "malformed error reply";
            protocol_error("the instrument refused " + std::string(p::to_string(type)) + ": " + code);
        }
        if (r.type != p::reply_type(type)) {
            protocol_error("answered " + std::string(p::to_string(type)) + " with " +
                           std::string(p::to_string(r.type)));
        }
        return r;
    }
    if (stats_.unknown_version_frames > foreign_before) {
        protocol_error("no protocol-version-" + std::to_string(p::kVersion) + " answer to " +
                       std::string(p::to_string(type)) + "; the instrument sent frames of protocol version " +
                       std::to_string(stats_.unknown_version) + ", which this ballbar does not speak");
    }
    throw DeviceError(DeviceErrorKind::Timeout, transport_->uri() + ": no answer to " +
                                                    std::string(p::to_string(type)) + " within " +
                                                    std::to_string(options_.reply_timeout.count()) + " ms (" +
                                                    std::to_string(options_.attempts) + " attempts)");
}

const InstrumentInfo& Instrument::identify() {
    const Reply r = request(p::MsgType::Identify, {});
    const auto id = p::parse_identify_reply(r.span());
    if (!id) protocol_error("malformed IdentifyReply");
    if (id->protocol_version != p::kVersion) {
        protocol_error("the instrument speaks protocol version " + std::to_string(id->protocol_version));
    }
    InstrumentInfo info;
    info.protocol_version = id->protocol_version;
    info.model = id->model;
    info.serial = id->serial;
    info.firmware = id->firmware;
    info.calibrated_length_mm = id->calibrated_length_nm * 1e-6;
    info.calibration_date = p::format_calibration_date(id->calibration_date);
    info.resolution_um = id->resolution_nm * 1e-3;
    info.range_mm = id->range_nm * 1e-6;
    info_ = info;
    return *info_;
}

InstrumentStatus Instrument::status() {
    const Reply r = request(p::MsgType::Status, {});
    const auto st = p::parse_status_reply(r.span());
    if (!st) protocol_error("malformed StatusReply");
    InstrumentStatus s;
    s.battery_pct = st->battery_pct;
    s.battery_V = st->battery_mV * 1e-3;
    s.bar_temp_C = st->bar_temp_cC * 0.01;
    s.error_flags = st->error_flags;
    s.streaming = st->streaming;
    s.sample_rate_hz = st->sample_rate_hz;
    s.averaging = st->averaging;
    s.referenced = st->referenced;
    return s;
}

void Instrument::configure(int sample_rate_hz, int averaging) {
    if (sample_rate_hz < p::kMinSampleRateHz || sample_rate_hz > p::kMaxSampleRateHz) {
        throw std::invalid_argument("sample rate must be 1..5000 Hz, not " + std::to_string(sample_rate_hz));
    }
    if (averaging < 1 || averaging > p::kMaxAveraging) {
        throw std::invalid_argument("averaging must be 1..64, not " + std::to_string(averaging));
    }
    const std::array<std::uint8_t, 3> body{static_cast<std::uint8_t>(sample_rate_hz & 0xFF),
                                           static_cast<std::uint8_t>(sample_rate_hz >> 8),
                                           static_cast<std::uint8_t>(averaging)};
    const Reply r = request(p::MsgType::Configure, body);
    const auto cfg = p::parse_configure(r.span());
    if (!cfg || cfg->sample_rate_hz != sample_rate_hz || cfg->averaging != averaging) {
        protocol_error("the instrument did not take the configuration");
    }
}

void Instrument::set_reference() {
    request(p::MsgType::SetReference, {});
}

void Instrument::start_streaming() {
    request(p::MsgType::Start, {});
    streaming_ = true;
    last_heartbeat_ = steady_clock::now();
}

void Instrument::stop_streaming() {
    request(p::MsgType::Stop, {});
    streaming_ = false;
}

std::uint64_t Instrument::heartbeat() {
    const std::uint32_t token = ++heartbeat_token_;
    const std::array<std::uint8_t, 4> body{static_cast<std::uint8_t>(token), static_cast<std::uint8_t>(token >> 8),
                                           static_cast<std::uint8_t>(token >> 16),
                                           static_cast<std::uint8_t>(token >> 24)};
    const Reply r = request(p::MsgType::Heartbeat, body);
    const auto hb = p::parse_heartbeat_reply(r.span());
    if (!hb || hb->token != token) protocol_error("malformed HeartbeatReply");
    return hb->uptime_us;
}

}  // namespace ballbar::device
