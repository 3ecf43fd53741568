// SPDX-License-Identifier: MIT
#include "ballbar/acquisition/dwell.hpp"

#include <cmath>
#include <stdexcept>

namespace ballbar::acquisition {

using analysis::BarSample;

DwellDetector::DwellDetector(const DwellSettings& settings) : settings_(settings) {
    if (settings_.window < 3) throw std::invalid_argument("dwell window must hold at least 3 samples");
    ring_.assign(settings_.window, 0.0);
}

void DwellDetector::clear() {
    head_ = count_ = since_recompute_ = 0;
    s1_ = s2_ = sxt_ = temp_sum_ = 0;
    temp_n_ = 0;
    flagged_ = false;
}

void DwellDetector::reset(bool armed) {
    clear();
    armed_ = armed;
    mode_ = Mode::Searching;
}

void DwellDetector::capture_now() {
    clear();
    mode_ = Mode::Capturing;
}

void DwellDetector::add(double x, const BarSample& s) {
    const std::size_t w = ring_.size();
    if (count_ < w) {
        // Growing: position of the new sample is count_.
        ring_[(head_ + count_) % w] = x;
        sxt_ += static_cast<double>(count_) * x;
        s1_ += x;
        s2_ += x * x;
        ++count_;
        if (count_ == 1) {
            first_seq_ = s.seq;
            first_time_ = s.device_time_us;
        }
    } else {
        // Sliding: drop ring_[head_], append x (derivation in docs/procedure.md).
        const double old = ring_[head_];
        ring_[head_] = x;
        head_ = (head_ + 1) % w;
        sxt_ = sxt_ + static_cast<double>(w) * x - (s1_ - old + x);
        s1_ += x - old;
        s2_ += x * x - old * old;
        ++first_seq_;
        if (++since_recompute_ >= w) recompute();
    }
    last_seq_ = s.seq;
    last_time_ = s.device_time_us;
}

void DwellDetector::recompute() {
    const std::size_t w = ring_.size();
    s1_ = s2_ = sxt_ = 0;
    for (std::size_t k = 0; k < count_; ++k) {
        const double x = ring_[(head_ + k) % w];
        s1_ += x;
        s2_ += x * x;
        sxt_ += static_cast<double>(k) * x;
    }
    since_recompute_ = 0;
}

void DwellDetector::compute(WindowStats& out) const {
    const double n = static_cast<double>(count_);
    const double mean = s1_ / n;
    const double var = std::max(0.0, (s2_ - n * mean * mean) / (n - 1));
    // Least-squares slope of x against k = 0..n−1.
    const double kmean = (n - 1) / 2;
    const double skk = n * (n * n - 1) / 12;
    const double slope = (sxt_ - kmean * s1_) / skk;
    out.mean_mm = expected_mm_ + mean;
    out.std_mm = std::sqrt(var);
    out.drift_mm = slope * (n - 1);
    out.n = count_;
    out.first_seq = first_seq_;
    out.last_seq = last_seq_;
    out.first_time_us = first_time_;
    out.last_time_us = last_time_;
    // The mean to 0.1 mK: a tenth of the samples' resolution, no float noise.
    out.bar_temp_C = temp_n_ > 0
                         ? std::optional<double>(analysis::decimal_round(temp_sum_ / static_cast<double>(temp_n_), 4))
                         : std::nullopt;
    out.flagged = flagged_;
}

DwellDetector::Result DwellDetector::push(const BarSample& s) {
    last_mm_ = s.length_mm(settings_.calibrated_length_mm);
    if (s.flags & analysis::kSampleOutOfRange) {
        // Out of range: the bar is moving (or off); anything collected is void.
        clear();
        armed_ = true;
        mode_ = Mode::Searching;
        return Result::None;
    }
    const double x = last_mm_ - expected_mm_;
    if (mode_ == Mode::Capturing) {
        add(x, s);
        if (!(s.flags & analysis::kSampleTempInvalid)) {
            temp_sum_ += s.temperature_C();
            ++temp_n_;
        }
        if (s.flags & ~analysis::kSampleTempInvalid) flagged_ = true;
        const std::size_t w = ring_.size();
        // The span of a full window: (w − 1) sample periods.
        const double span_s = settings_.window_s * static_cast<double>(w - 1) / static_cast<double>(w);
        const bool spans = settings_.window_s > 0 && 2 * count_ >= w && count_ >= 3 &&
                           1e-6 * static_cast<double>(last_time_ - first_time_) >= span_s;
        if (count_ < w && !spans) return Result::None;
        compute(stats_);
        clear();
        mode_ = Mode::Searching;
        armed_ = false;
        return Result::Captured;
    }
    add(x, s);
    if (count_ < ring_.size()) return Result::None;
    WindowStats w;
    compute(w);
    const bool still = w.std_mm <= settings_.still_std_mm && std::abs(w.drift_mm) <= settings_.still_drift_mm;
    if (!still) {
        armed_ = true;
        return Result::None;
    }
    if (!armed_ || std::abs(w.mean_mm - expected_mm_) > settings_.tolerance_mm) return Result::None;
    capture_now();
    return Result::Settled;
}

}  // namespace ballbar::acquisition
