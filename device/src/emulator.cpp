// SPDX-License-Identifier: MIT
// The emulated instrument: protocol handling, sampling, fault injection.
#include "ballbar/device/emulator.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "ballbar/analysis/sample.hpp"
#include "ballbar/fileio/input.hpp"

namespace ballbar::device {

namespace p = protocol;

namespace {
constexpr std::size_t kOutputLimit = 256 * 1024;  ///< the device's transmit buffer
constexpr std::uint64_t kFlushUs = 20'000;        ///< a partial stream frame waits at most this long
}  // namespace

Emulator::Emulator(EmulatorConfig config)
    : config_(std::move(config)),
      machine_(config_.machine),
      rng_(config_.seed),
      rate_hz_(config_.instrument.sample_rate_hz),
      averaging_(config_.instrument.averaging) {
    out_.reserve(kOutputLimit + p::kMaxFrameSize);
    if (config_.continuous) {
        ContinuousSetup cs;
        cs.errors = *config_.continuous;
        const auto& m = config_.machine;
        cs.start_mm = {m.start.X_mm, m.start.Y_mm, m.start.Z_mm};
        cs.socket_mm = {m.socket_mm.x(), m.socket_mm.y(), m.socket_mm.z()};
        cs.socket_offset_mm = {m.socket_offset_mm.x(), m.socket_offset_mm.y(), m.socket_offset_mm.z()};
        cs.rapid_mm_min = m.rapid_mm_min;
        continuous_ = std::make_unique<ContinuousMachine>(cs);
    }
    if (config_.program && config_.program->power_on) {
        if (continuous_) {
            continuous_->run_program(config_.program->text, config_.program->dialect, 0.0);
        } else {
            machine_.run_nc(config_.program->text, config_.program->dialect);
        }
        program_started_ = true;
        loaded_program_ = config_.program->text;
    }
}

void Emulator::cycle_start() {
    // The host starts streaming when it has told the operator to start the program or to press cycle
    // start at a program stop: the emulated operator does so (docs/emulator.md).
    if (!config_.program || config_.program->power_on) return;
    ++counters_.cycle_starts;
    const double t_s = static_cast<double>(now_us_) * 1e-6;
    NcSource& src = *config_.program;
    if (!src.file.empty()) {
        try {
            const std::string text = fileio::read_text(src.file, "NC program");  // capped; regular files only
            if (continuous_)
                parse_motion_program(text, src.dialect, {0, 0, 0}, 1.0);
            else
                analysis::parse_nc_program(text, src.dialect);
            if (!text.empty()) src.text = text;
        } catch (const fileio::FileError&) {
            // gone, unreadable or too large: keep the last program
        } catch (const analysis::NcError&) {
            // a half-written file: keep the last program
        }
    }
    if (src.text.empty()) return;
    if (continuous_) {
        // Continuous motion has no program stops: each cycle start runs the program from its start (the
        // operator resets a program still running and starts it again).
        continuous_->run_program(src.text, src.dialect, t_s);
        program_started_ = true;
        loaded_program_ = src.text;
        ++counters_.programs_started;
        return;
    }
    const bool new_program = !program_started_ || src.text != loaded_program_;
    if (!new_program && machine_.holding()) {
        machine_.cycle_start(t_s);  // at (or on the way to) a program stop: the rest runs
        return;
    }
    if (!new_program && !machine_.idle_at(t_s)) return;  // cycle start while running does nothing
    machine_.stop(t_s);  // a new program (or the same again): reset, then run it from the start
    machine_.run_nc(src.text, src.dialect);
    program_started_ = true;
    loaded_program_ = src.text;
    ++counters_.programs_started;
}

double Emulator::uniform() {
    return static_cast<double>(rng_() >> 11) * 0x1.0p-53;
}

double Emulator::gaussian() {
    // Box–Muller on our own uniform draws: the same numbers on every standard library.
    const double u1 = 1.0 - uniform();
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * analysis::kPi * u2);
}

double Emulator::bar_temp_C(std::uint64_t t_us) const {
    const auto& in = config_.instrument;
    const double t_s = static_cast<double>(t_us) * 1e-6;
    double ripple = 0;
    if (in.temp_ripple_period_s > 0)
        ripple = in.temp_ripple_C * std::sin(2.0 * analysis::kPi * t_s / in.temp_ripple_period_s);
    return in.temp_start_C + in.temp_drift_C_per_h * t_s / 3600.0 + ripple;
}

p::StatusReply Emulator::status() const {
    const auto& in = config_.instrument;
    p::StatusReply s;
    const double pct = std::clamp(
        in.battery_start_pct - in.battery_drain_pct_per_h * static_cast<double>(now_us_) * 1e-6 / 3600.0, 0.0, 100.0);
    s.battery_pct = static_cast<std::uint8_t>(std::lround(pct));
    s.battery_mV = static_cast<std::uint16_t>(3300 + std::lround(9.0 * pct));
    s.bar_temp_cC = static_cast<std::int16_t>(std::lround(bar_temp_C(now_us_) * 100.0));
    s.error_flags =
        static_cast<std::uint16_t>((pct < 10 ? p::kStatusLowBattery : 0) | (overrun_ ? p::kStatusOverrun : 0));
    s.streaming = streaming_;
    s.sample_rate_hz = rate_hz_;
    s.averaging = averaging_;
    s.referenced = referenced_;
    return s;
}

void Emulator::emit(const p::FrameBuffer& buf, std::size_t n) {
    const std::size_t at = out_.size();
    out_.insert(out_.end(), buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(n));
    const double pc = config_.faults.corrupt_byte_probability;
    if (pc > 0) {
        for (std::size_t i = at; i < out_.size(); ++i) {
            if (uniform() < pc) {
                out_[i] = static_cast<std::uint8_t>(out_[i] ^ (1u << (rng_() % 8)));
                ++counters_.corrupted_bytes;
            }
        }
    }
}

void Emulator::reply(const p::FrameBuffer& buf, std::size_t n) {
    if (config_.faults.reply_delay_ms > 0) {
        const auto delay = static_cast<std::uint64_t>(config_.faults.reply_delay_ms * 1000.0);
        delayed_.push_back({now_us_ + delay, buf, n});
    } else {
        emit(buf, n);
    }
}

void Emulator::on_host_bytes(std::span<const std::uint8_t> data) {
    if (!connected_) return;  // nobody is listening
    const auto& f = config_.faults;
    const double t_s = static_cast<double>(now_us_) * 1e-6;
    if (f.stall_at_s >= 0 && t_s >= f.stall_at_s && t_s < f.stall_at_s + f.stall_s) {
        stalled_input_.insert(stalled_input_.end(), data.begin(), data.end());
        return;
    }
    while (!data.empty()) {
        const auto r = decoder_.next(data);
        if (r.status == p::DecodeStatus::Frame) {
            handle(r.frame);
        } else if (r.status == p::DecodeStatus::Invalid) {
            ++counters_.invalid_host_frames;
        }
    }
}

void Emulator::handle(const p::FrameView& frame) {
    ++counters_.requests;
    last_host_us_ = now_us_;
    p::FrameBuffer buf{};
    const auto error = [&](p::ErrorCode code) {
        reply(buf, p::encode(p::ErrorReply{code, static_cast<std::uint8_t>(frame.type)}, frame.seq, buf));
    };
    if (frame.version != p::kVersion) return error(p::ErrorCode::UnsupportedVersion);
    const bool empty = frame.body.empty();
    switch (frame.type) {
        case p::MsgType::Identify: {
            if (!empty) return error(p::ErrorCode::BadLength);
            p::IdentifyReply id;
            id.model = config_.instrument.model.substr(0, 12);
            id.serial = config_.instrument.serial.substr(0, 12);
            id.firmware = config_.instrument.firmware.substr(0, 8);
            id.calibrated_length_nm =
                static_cast<std::uint32_t>(std::llround(config_.instrument.calibrated_length_mm * 1e6));
            id.calibration_date = p::parse_calibration_date(config_.instrument.calibration_date).value_or(0);
            return reply(buf, p::encode(id, frame.seq, buf));
        }
        case p::MsgType::Status:
            if (!empty) return error(p::ErrorCode::BadLength);
            return reply(buf, p::encode(status(), frame.seq, buf));
        case p::MsgType::Configure: {
            const auto cfg = p::parse_configure(frame.body);
            if (!cfg) return error(p::ErrorCode::BadLength);
            if (streaming_) return error(p::ErrorCode::Busy);
            if (cfg->sample_rate_hz < p::kMinSampleRateHz || cfg->sample_rate_hz > p::kMaxSampleRateHz ||
                cfg->averaging < 1 || cfg->averaging > p::kMaxAveraging) {
                return error(p::ErrorCode::OutOfRange);
            }
            rate_hz_ = cfg->sample_rate_hz;
            averaging_ = cfg->averaging;
            return reply(buf,
                         p::encode(p::ConfigureBody{rate_hz_, averaging_}, p::MsgType::ConfigureReply, frame.seq, buf));
        }
        case p::MsgType::Start:
            if (!empty) return error(p::ErrorCode::BadLength);
            flush_stream();
            cycle_start();
            streaming_ = true;
            stream_seq_ = 0;
            sample_index_ = 0;
            period_ns_ = static_cast<std::uint32_t>(1'000'000'000u / rate_hz_);
            stream_start_ns_ = now_us_ * 1000;
            pending_.count = 0;
            return reply(buf, p::encode_empty(p::MsgType::StartReply, frame.seq, buf));
        case p::MsgType::Stop:
            if (!empty) return error(p::ErrorCode::BadLength);
            produce_samples_until(now_us_);
            flush_stream();
            streaming_ = false;
            return reply(buf, p::encode_empty(p::MsgType::StopReply, frame.seq, buf));
        case p::MsgType::SetReference:
            if (!empty) return error(p::ErrorCode::BadLength);
            if (streaming_) return error(p::ErrorCode::Busy);
            referenced_ = true;
            return reply(buf, p::encode_empty(p::MsgType::SetReferenceReply, frame.seq, buf));
        case p::MsgType::Heartbeat: {
            const auto token = p::parse_heartbeat(frame.body);
            if (!token) return error(p::ErrorCode::BadLength);
            return reply(buf, p::encode(p::HeartbeatReply{*token, now_us_}, frame.seq, buf));
        }
        default:
            return error(p::ErrorCode::UnknownType);
    }
}

void Emulator::flush_stream() {
    if (pending_.count == 0) return;
    p::FrameBuffer buf{};
    const std::size_t n = p::encode(pending_, stream_seq_, buf);
    ++stream_seq_;
    pending_.count = 0;
    if (pending_output() > kOutputLimit) {  // the host is not reading: the device drops and says so
        overrun_ = true;
        ++counters_.dropped_frames;
        return;
    }
    const double pd = config_.faults.drop_frame_probability;
    if (pd > 0 && uniform() < pd) {
        ++counters_.dropped_frames;
        return;
    }
    ++counters_.stream_frames;
    emit(buf, n);
    const double pr = config_.faults.replay_frame_probability;
    if (pr > 0 && uniform() < pr) {
        ++counters_.replayed_frames;
        emit(buf, n);
    }
}

void Emulator::produce_samples_until(std::uint64_t t_us) {
    if (!streaming_) return;
    const auto& in = config_.instrument;
    const double L = in.calibrated_length_mm;
    const double noise_nm = in.noise_um * 1000.0 / std::sqrt(static_cast<double>(averaging_));
    const double zero_nm = referenced_ ? 0.0 : in.zero_offset_um * 1000.0;
    const std::uint64_t end_ns = t_us * 1000;
    while (true) {
        const std::uint64_t t_ns = stream_start_ns_ + sample_index_ * period_ns_;
        if (t_ns > end_ns) break;
        const std::uint64_t ts_us = t_ns / 1000;
        if (pending_.count == 0) {
            pending_.t0_us = ts_us;
            pending_.period_ns = period_ns_;
            pending_.bar_temp_cC = static_cast<std::int16_t>(std::lround(bar_temp_C(ts_us) * 100.0));
            pending_first_us_ = ts_us;
        }
        const double temp = bar_temp_C(ts_us);
        const double t_sample_s = static_cast<double>(t_ns) * 1e-9;
        const double reading =
            continuous_ ? continuous_->bar_length_mm(t_sample_s) : machine_.bar_reading_mm(t_sample_s, temp);
        const double disp_nm = (reading - L) * 1e6 + zero_nm + noise_nm * gaussian();
        long steps = std::lround(disp_nm / static_cast<double>(p::kResolutionNm));
        std::uint8_t flags = referenced_ ? 0 : analysis::kSampleNotReferenced;
        if (steps > p::kDisplacementLimit || steps < -p::kDisplacementLimit) {
            steps = std::clamp<long>(steps, -p::kDisplacementLimit, p::kDisplacementLimit);
            flags = static_cast<std::uint8_t>(flags | analysis::kSampleOutOfRange);
        }
        pending_.samples[pending_.count++] = {static_cast<std::int16_t>(steps), flags};
        ++sample_index_;
        ++counters_.samples;
        if (pending_.count == p::kMaxSamplesPerFrame) flush_stream();
    }
    if (pending_.count > 0 && t_us >= pending_first_us_ + kFlushUs) flush_stream();
}

void Emulator::host_link_lost() {
    const bool was = connected_;
    go_disconnected();
    connected_ = was;
}

void Emulator::go_disconnected() {
    connected_ = false;
    streaming_ = false;
    pending_.count = 0;
    out_.clear();
    out_head_ = 0;
    delayed_.clear();
    stalled_input_.clear();
    decoder_.reset();
}

void Emulator::advance_to(std::uint64_t t_us) {
    if (t_us <= now_us_) return;
    const auto& f = config_.faults;
    if (f.disconnect_at_s >= 0 && !disconnect_done_) {
        const auto start = static_cast<std::uint64_t>(f.disconnect_at_s * 1e6);
        const auto end = start + static_cast<std::uint64_t>(f.disconnect_s * 1e6);
        if (connected_ && t_us >= start) {
            if (start > now_us_) {
                produce_samples_until(start);
                now_us_ = start;
            }
            go_disconnected();
        }
        if (!connected_) {
            if (t_us < end) {
                now_us_ = t_us;
                return;
            }
            connected_ = true;
            disconnect_done_ = true;
            ++epoch_;
            now_us_ = end;
            last_host_us_ = end;
        }
    }
    produce_samples_until(t_us);
    now_us_ = t_us;
    // The machine's clock follows the emulator's whether or not the bar streams: motion queued now
    // (a program, a cycle start) starts now.
    machine_.pose_at(static_cast<double>(now_us_) * 1e-6);
    while (!delayed_.empty() && delayed_.front().release_us <= now_us_) {
        emit(delayed_.front().bytes, delayed_.front().size);
        delayed_.pop_front();
    }
    const double t_s = static_cast<double>(now_us_) * 1e-6;
    if (!stalled_input_.empty() && !(f.stall_at_s >= 0 && t_s >= f.stall_at_s && t_s < f.stall_at_s + f.stall_s)) {
        std::vector<std::uint8_t> input;
        input.swap(stalled_input_);
        on_host_bytes(input);
    }
    const auto& in = config_.instrument;
    if (!external_watchdog_ && streaming_ && in.watchdog_s > 0 &&
        static_cast<double>(now_us_ - last_host_us_) * 1e-6 > in.watchdog_s)
        watchdog_expired();
}

void Emulator::watchdog_expired() {
    if (!streaming_) return;
    flush_stream();
    streaming_ = false;
}

std::size_t Emulator::take_device_bytes(std::span<std::uint8_t> out) {
    if (!connected_) return 0;
    const auto& f = config_.faults;
    const double t_s = static_cast<double>(now_us_) * 1e-6;
    if (f.stall_at_s >= 0 && t_s >= f.stall_at_s && t_s < f.stall_at_s + f.stall_s) return 0;
    const std::size_t n = std::min(out.size(), pending_output());
    if (n > 0) std::memcpy(out.data(), out_.data() + out_head_, n);
    out_head_ += n;
    if (out_head_ == out_.size()) {
        out_.clear();
        out_head_ = 0;
    } else if (out_head_ > 64 * 1024) {
        out_.erase(out_.begin(), out_.begin() + static_cast<std::ptrdiff_t>(out_head_));
        out_head_ = 0;
    }
    return n;
}

}  // namespace ballbar::device
