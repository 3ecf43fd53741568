// SPDX-License-Identifier: MIT
#include <thread>

#include "ballbar/device/gauge.hpp"

namespace ballbar::device::gauge {

GaugeSampler::GaugeSampler(std::unique_ptr<Gauge> gauge, BarOnGauge bar, Clock clock)
    : gauge_(std::move(gauge)), bar_(bar), clock_(std::move(clock)) {
    if (!(bar_.target_rate_hz > 0)) throw std::invalid_argument("gauge rate must be positive");
    if (bar_.sign != 1.0 && bar_.sign != -1.0) throw std::invalid_argument("gauge sign must be +1 or -1");
    if (!clock_) {
        const auto start = std::chrono::steady_clock::now();
        clock_ = [start] {
            return static_cast<std::uint64_t>(
                std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - start)
                    .count());
        };
        real_time_ = true;
    }
}

const Identity& GaugeSampler::identify() {
    if (!identity_) identity_ = gauge_->identify();
    return *identity_;
}

void GaugeSampler::note_time(std::uint64_t t_us) {
    if (rate_n_ == 0) rate_t0_us_ = t_us;
    ++rate_n_;
    if (rate_n_ > 1 && t_us > rate_t0_us_)
        stats_.rate_hz = static_cast<double>(rate_n_ - 1) * 1e6 / static_cast<double>(t_us - rate_t0_us_);
}

std::optional<Reading> GaugeSampler::read_one(std::chrono::milliseconds timeout) {
    const auto period_us = static_cast<std::uint64_t>(1e6 / bar_.target_rate_hz);
    if (real_time_) {
        const std::uint64_t now = clock_();
        if (next_due_us_ > now) std::this_thread::sleep_for(std::chrono::microseconds(next_due_us_ - now));
    }
    next_due_us_ = std::max(next_due_us_ + period_us, clock_());
    Reading r;
    try {
        r = gauge_->read(timeout);
    } catch (const DeviceError& e) {
        gap_ = true;
        if (e.kind() == DeviceErrorKind::Timeout) {
            ++stats_.timeouts;
            return std::nullopt;
        }
        if (e.kind() == DeviceErrorKind::Protocol) {
            ++stats_.invalid;
            return std::nullopt;
        }
        throw;
    }
    switch (r.status) {
        case ReadingStatus::Ok:
            break;
        case ReadingStatus::NotReady:
            ++stats_.not_ready;
            gap_ = true;
            return std::nullopt;
        case ReadingStatus::OutOfRange:
            ++stats_.out_of_range;
            gap_ = true;
            return std::nullopt;
        case ReadingStatus::Error:
            ++stats_.errors;
            gap_ = true;
            return std::nullopt;
    }
    ++stats_.readings;
    const double res = r.resolution_mm();
    if (stats_.resolution_mm == 0 || res < stats_.resolution_mm) stats_.resolution_mm = res;
    note_time(clock_());
    return r;
}

void GaugeSampler::measure(int n) {
    for (int i = 0, tries = 0; i < n && tries < 4 * n; ++tries) {
        if (read_one(std::chrono::milliseconds(1000))) ++i;
    }
}

void GaugeSampler::set_zero(int n) {
    double sum = 0;
    int got = 0;
    for (int tries = 0; got < n && tries < 4 * n; ++tries) {
        if (auto r = read_one(std::chrono::milliseconds(1000))) {
            sum += r->value_mm();
            ++got;
        }
    }
    if (got == 0) throw DeviceError(DeviceErrorKind::Timeout, gauge_->uri() + ": no reading to set the zero with");
    zero_mm_ = sum / got;
    gap_ = false;
}

std::optional<analysis::BarSample> GaugeSampler::poll(std::chrono::milliseconds timeout) {
    const auto r = read_one(timeout);
    if (!r) return std::nullopt;
    analysis::BarSample s;
    s.device_time_us = clock_();
    s.displacement_nm = to_nm(bar_.sign * (r->value_mm() - zero_mm_.value_or(0.0)));
    // A gauge has no bar thermometer: its samples say so rather than carry the default 20 °C.
    s.flags = analysis::kSampleTempInvalid;
    if (!zero_mm_) s.flags = static_cast<std::uint16_t>(s.flags | analysis::kSampleNotReferenced);
    if (gap_) s.flags = static_cast<std::uint16_t>(s.flags | analysis::kSampleAfterGap);
    gap_ = false;
    return s;
}

}  // namespace ballbar::device::gauge
