// SPDX-License-Identifier: MIT
// The gauges' device side (docs/instruments.md gives each grammar; this file speaks them).
#include <cmath>
#include <cstdio>

#include "ballbar/device/gauge_emulator.hpp"

namespace ballbar::device::gauge {

std::array<std::uint8_t, 13> encode_spc_frame(double value, int decimals, bool inch) {
    std::array<std::uint8_t, 13> n{};
    for (int i = 0; i < 4; ++i) n[static_cast<std::size_t>(i)] = 0xF;
    n[4] = value < 0 ? 8 : 0;
    auto digits = static_cast<long long>(std::llround(std::abs(value) * std::pow(10.0, decimals)));
    if (digits > 999999) digits = 999999;
    for (std::size_t i = 10; i >= 5; --i) {
        n[i] = static_cast<std::uint8_t>(digits % 10);
        digits /= 10;
    }
    n[11] = static_cast<std::uint8_t>(decimals);
    n[12] = inch ? 1 : 0;
    return n;
}

std::uint16_t modbus_crc(std::span<const std::uint8_t> data) {
    std::uint16_t crc = 0xFFFF;
    for (const std::uint8_t b : data) {
        crc ^= b;
        for (int i = 0; i < 8; ++i) crc = (crc & 1) ? static_cast<std::uint16_t>((crc >> 1) ^ 0xA001) : crc >> 1;
    }
    return crc;
}

GaugeEmulator::GaugeEmulator(GaugeEmulatorConfig config, Displacement displacement, bool simulated_clock)
    : config_(std::move(config)),
      displacement_(std::move(displacement)),
      simulated_(simulated_clock),
      start_(std::chrono::steady_clock::now()),
      rng_(config_.seed) {}

std::uint64_t GaugeEmulator::now_us() const {
    if (simulated_) return sim_us_.load();
    return static_cast<std::uint64_t>(
        std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - start_).count());
}

void GaugeEmulator::set_faults(const GaugeFaults& f) {
    std::lock_guard lock(m_);
    config_.faults = f;
}

void GaugeEmulator::tick() {
    ++requests_;
    const auto period = static_cast<std::uint64_t>(std::llround(1e6 / config_.rate_hz));
    if (simulated_) {
        sim_us_ += period;
    } else {  // a real gauge answers at its own pace: one reading per period at most
        release_us_ = std::max(now_us(), release_us_ + period);
    }
}

GaugeEmulator::Fault GaugeEmulator::draw_fault() {
    const GaugeFaults& f = config_.faults;
    double u = uniform_(rng_);
    for (const auto& [p, fault] :
         {std::pair{f.no_reply_probability, Fault::NoReply}, std::pair{f.cut_off_probability, Fault::CutOff},
          std::pair{f.not_ready_probability, Fault::NotReady},
          std::pair{f.out_of_range_probability, Fault::OutOfRange}}) {
        if (u < p) return fault;
        u -= p;
    }
    return Fault::None;
}

bool GaugeEmulator::sample_value(double& value, int& decimals) {
    const double t_s = static_cast<double>(now_us()) * 1e-6;
    const double disp = in_calibrator_ || !displacement_ ? 0.0 : displacement_(t_s);
    double mm = config_.offset_mm + config_.sign * disp + config_.noise_um * 1e-3 * gauss_(rng_);
    const bool beyond = std::abs(mm) > config_.range_mm;
    double step = config_.resolution_mm;
    if (config_.faults.inch) {
        mm /= 25.4;
        step = std::max(0.00001, std::pow(10.0, std::round(std::log10(step / 25.4))));
    }
    decimals = std::clamp(static_cast<int>(std::lround(-std::log10(step))), 0, 5);
    value = std::round(mm / step) * step;
    return !beyond;
}

void GaugeEmulator::send(std::deque<std::uint8_t>& q, const std::string& reply, Fault f) {
    const std::size_t n = f == Fault::CutOff ? reply.size() / 2 : reply.size();
    q.insert(q.end(), reply.begin(), reply.begin() + static_cast<std::ptrdiff_t>(n));
}

// ---- Sylvac ----------------------------------------------------------------------------------------

namespace {

std::string fixed(double v, int int_digits, int decimals) {
    char buf[48];
    std::snprintf(buf, sizeof buf, "%+0*.*f", int_digits + decimals + (decimals > 0 ? 2 : 1), decimals, v);
    return buf;
}

}  // namespace

void GaugeEmulator::on_sylvac_line(const std::string& line) {
    if (line == "?") {
        tick();
        const Fault f = draw_fault();
        if (f == Fault::NoReply) return;
        double v = 0;
        int dec = 0;
        const bool ok = sample_value(v, dec);
        if (f == Fault::NotReady) return send(out_, "E1\r", f);
        if (f == Fault::OutOfRange || !ok) return send(out_, "E2\r", f);
        return send(out_, fixed(v, config_.faults.inch ? 2 : 3, dec) + "\r", f);
    }
    if (line == "UNI?") return send(out_, config_.faults.inch ? "IN\r" : "MM\r", Fault::None);
    if (line == "BAT?") return send(out_, config_.faults.low_battery ? "BAT0\r" : "BAT1\r", Fault::None);
    if (line == "REF?") return send(out_, "REF0\r", Fault::None);
    // OFF, SBY, RST and anything else: no answer.
}

// ---- Modbus RTU ------------------------------------------------------------------------------------

void GaugeEmulator::on_modbus_bytes() {
    while (rtu_.size() >= 8) {
        const std::uint16_t crc = modbus_crc({rtu_.data(), 6});
        if (rtu_[6] != (crc & 0xff) || rtu_[7] != (crc >> 8)) {
            rtu_.erase(rtu_.begin());  // resynchronise on the next byte
            continue;
        }
        const std::uint8_t slave = rtu_[0];
        const std::uint8_t fn = rtu_[1];
        const unsigned addr = rtu_[2] << 8 | rtu_[3];
        const unsigned count = rtu_[4] << 8 | rtu_[5];
        rtu_.erase(rtu_.begin(), rtu_.begin() + 8);
        if (slave != config_.modbus_slave) continue;  // another device on the bus
        tick();
        const Fault f = draw_fault();
        if (f == Fault::NoReply) continue;
        std::vector<std::uint8_t> reply{slave, fn};
        auto exception = [&](std::uint8_t code) { reply = {slave, static_cast<std::uint8_t>(fn | 0x80), code}; };
        double v = 0;
        int dec = 0;
        const bool ok = sample_value(v, dec);
        if (fn != 0x03) {
            exception(0x01);  // illegal function
        } else if (addr != 0 || count != 2) {
            exception(0x02);  // illegal data address
        } else if (f == Fault::NotReady) {
            exception(0x06);  // slave device busy
        } else if (f == Fault::OutOfRange || !ok) {
            exception(0x04);  // slave device failure
        } else {
            const double mm = config_.faults.inch ? v * 25.4 : v;  // the register is always mm × 10⁴
            const auto raw = static_cast<std::uint32_t>(static_cast<std::int32_t>(std::llround(mm * 10000)));
            reply.insert(reply.end(), {4, static_cast<std::uint8_t>(raw >> 24), static_cast<std::uint8_t>(raw >> 16),
                                       static_cast<std::uint8_t>(raw >> 8), static_cast<std::uint8_t>(raw)});
        }
        const std::uint16_t c = modbus_crc(reply);
        reply.push_back(static_cast<std::uint8_t>(c & 0xff));
        reply.push_back(static_cast<std::uint8_t>(c >> 8));
        send(out_, std::string(reply.begin(), reply.end()), f);
    }
}

// ---- serial endpoint -------------------------------------------------------------------------------

void GaugeEmulator::on_host_bytes(std::span<const std::uint8_t> data) {
    std::lock_guard lock(m_);
    switch (config_.kind) {
        case Kind::Sylvac:
            for (const std::uint8_t b : data) {
                if (b == '\r') {
                    on_sylvac_line(line_);
                    line_.clear();
                } else if (b != '\n' && line_.size() < kMaxLine) {
                    line_.push_back(static_cast<char>(b & 0x7f));  // 7 data bits
                }
            }
            return;
        case Kind::Digimatic:
            for (std::size_t i = 0; i < data.size(); ++i) {  // any character: one reading
                tick();
                const Fault f = draw_fault();
                if (f == Fault::NoReply) continue;
                double v = 0;
                int dec = 0;
                const bool ok = sample_value(v, dec);
                if (f == Fault::NotReady) {
                    send(out_, "#NR\r\n", f);
                    continue;
                }
                if (f == Fault::OutOfRange || !ok) {
                    send(out_, "#OR\r\n", f);
                    continue;
                }
                // The adaptor clocks the gauge's SPC frame in and prints what it decodes.
                const auto frame = encode_spc_frame(v, dec, config_.faults.inch);
                const Decoded d = decode_spc_frame(frame);
                char buf[48];
                std::snprintf(buf, sizeof buf, "%+.*f%s\r\n", d.reading.decimals, d.reading.value,
                              d.reading.inch ? " in" : "");
                send(out_, buf, f);
            }
            return;
        case Kind::Modbus:
            rtu_.insert(rtu_.end(), data.begin(), data.end());
            on_modbus_bytes();
            return;
        case Kind::MitutoyoItn:
            return;  // not a serial device
    }
}

std::size_t GaugeEmulator::take_device_bytes(std::span<std::uint8_t> out) {
    std::lock_guard lock(m_);
    if (!simulated_ && now_us() < release_us_) return 0;
    const std::size_t n = std::min(out.size(), out_.size());
    std::copy_n(out_.begin(), n, out.begin());
    out_.erase(out_.begin(), out_.begin() + static_cast<std::ptrdiff_t>(n));
    return n;
}

// ---- USB-ITN ---------------------------------------------------------------------------------------

void GaugeEmulator::itn_command(const std::string& line) {
    if (line == "1") {
        tick();
        const Fault f = draw_fault();
        if (f == Fault::NoReply) return;
        double v = 0;
        int dec = 0;
        const bool ok = sample_value(v, dec);
        if (f == Fault::NotReady) return send(interrupt_, "918\r", f);
        if (f == Fault::OutOfRange || !ok) return send(interrupt_, "911\r", f);
        // D5..D12: eight characters with the decimal point.
        return send(interrupt_, "01A" + fixed(v, 7 - dec, dec) + "\r", f);
    }
    if (line == "V") return send(interrupt_, "USB-ITN EMU 1.00\r", Fault::None);
}

void GaugeEmulator::control_out(std::uint8_t request, std::uint16_t value, std::span<const std::uint8_t> data) {
    std::lock_guard lock(m_);
    if (request == kItnRequestInit && value == kItnInitValue) {
        itn_initialised_ = true;
        interrupt_.clear();
        return;
    }
    if (request != kItnRequestCommand || !itn_initialised_) return;
    for (const std::uint8_t b : data) {
        if (b == '\r') {
            itn_command(line_);
            line_.clear();
        } else if (line_.size() < kMaxLine) {
            line_.push_back(static_cast<char>(b));
        }
    }
}

int GaugeEmulator::control_in(std::uint8_t request, std::uint16_t, std::span<std::uint8_t> out) {
    std::lock_guard lock(m_);
    if (request != kItnRequestStatus || out.empty()) return -1;
    out[0] = itn_initialised_ ? 0x01 : 0x00;
    return 1;
}

std::size_t GaugeEmulator::take_interrupt(std::span<std::uint8_t> out) {
    std::lock_guard lock(m_);
    if (!simulated_ && now_us() < release_us_) return 0;
    const std::size_t n = std::min({out.size(), interrupt_.size(), std::size_t{8}});
    std::copy_n(interrupt_.begin(), n, out.begin());
    interrupt_.erase(interrupt_.begin(), interrupt_.begin() + static_cast<std::ptrdiff_t>(n));
    return n;
}

}  // namespace ballbar::device::gauge
