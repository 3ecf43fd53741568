// SPDX-License-Identifier: MIT
#include "ballbar/acquisition/attribution.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace ballbar::acquisition {

namespace {
std::string seconds(std::uint64_t us) {
    std::ostringstream os;
    os.setf(std::ios::fixed);
    os.precision(3);
    os << 1e-6 * static_cast<double>(us) << " s";
    return os.str();
}
}  // namespace

DwellAttributor::DwellAttributor(const AttributionSettings& settings)
    : settings_(settings), data_digits_(code_data_digits(settings.point_count)), detector_(settings.dwell) {
    const auto n = std::max<std::size_t>(
        5, static_cast<std::size_t>(std::lround(settings_.plateau_window_s * settings_.sample_rate_hz)));
    ring_.assign(n, 0.0);
    ring_time_.assign(n, 0);
}

std::string DwellAttributor::digits_text() const {
    std::string t;
    for (int d : digits_) t += std::to_string(d);
    for (std::size_t k = digits_.size(); k < tags_.size(); ++k) t += "?";
    return t;
}

AttributionEvent DwellAttributor::reset(const std::string& why) {
    AttributionEvent ev;
    if (measuring_) {
        ev = void_measurement(why);
    } else if (!tags_.empty()) {
        ev.kind = AttributionEvent::Kind::Void;
        ev.evidence = "code " + digits_text() + "… not finished: " + why;
    }
    digits_.clear();
    tags_.clear();
    head_ = count_ = since_recompute_ = 0;
    s1_ = s2_ = 0;
    in_plateau_ = false;
    last_time_us_.reset();
    return ev;
}

AttributionEvent DwellAttributor::void_measurement(const std::string& why) {
    AttributionEvent ev;
    ev.kind = AttributionEvent::Kind::Void;
    ev.point = measuring_;
    ev.evidence = measuring_evidence_ + "; dwell void: " + why;
    measuring_.reset();
    held_.reset();
    detector_.reset(true);
    return ev;
}

void DwellAttributor::close_plateau() {
    if (!in_plateau_) return;
    in_plateau_ = false;
    const double level = level_sum_ / static_cast<double>(level_n_);
    const double dur = 1e-6 * static_cast<double>(plateau_last_us_ - plateau_start_us_);
    const PointCodeSpec& c = settings_.code;
    const bool tag_time = dur >= c.min_plateau_s && dur <= c.max_plateau_s;
    // A tag candidate: on the side its position says, between the smallest and the largest tag offset
    // with room for the machine's error at this point (the digits are read relative to the measuring
    // level that follows, so an error common to the code and its dwell cancels).
    auto candidate = [&](int pos) {
        const double lo = settings_.measuring_level_mm;
        const double hi = c.min_offset_mm + 2 * c.digit_step_mm + 2 * c.decision_mm;
        const double signed_level = pos % 2 == 0 ? -level : level;
        return tag_time && signed_level >= lo && signed_level <= hi;
    };
    const int pos = static_cast<int>(tags_.size());
    if (pos <= data_digits_ && candidate(pos)) {
        if (tags_.empty()) code_start_us_ = plateau_start_us_;
        tags_.push_back(level);
        return;
    }
    // Not the next tag: perhaps the first tag of a new code.
    tags_.clear();
    if (candidate(0)) {
        code_start_us_ = plateau_start_us_;
        tags_.push_back(level);
    }
}

AttributionEvent DwellAttributor::push(const analysis::BarSample& s) {
    AttributionEvent ev;
    last_mm_ = s.length_mm(settings_.dwell.calibrated_length_mm);
    const std::uint64_t t = s.device_time_us;
    // A gap long enough to hide a plateau voids what is being read.
    if (last_time_us_ && t > *last_time_us_ &&
        1e-6 * static_cast<double>(t - *last_time_us_) > settings_.code.max_gap_s) {
        const std::string why = "stream gap of " + seconds(t - *last_time_us_) + " at " + seconds(*last_time_us_);
        ev = reset(why);
    }
    last_time_us_ = t;
    const bool out_of_range = (s.flags & analysis::kSampleOutOfRange) != 0;
    const double x = last_mm_ - settings_.bar_length_mm;

    // Plateau detector.
    const std::size_t w = ring_.size();
    if (out_of_range) {
        head_ = count_ = 0;
        s1_ = s2_ = 0;
    } else if (count_ < w) {
        ring_[(head_ + count_) % w] = x;
        ring_time_[(head_ + count_) % w] = t;
        s1_ += x;
        s2_ += x * x;
        ++count_;
    } else {
        const double old = ring_[head_];
        ring_[head_] = x;
        ring_time_[head_] = t;
        head_ = (head_ + 1) % w;
        s1_ += x - old;
        s2_ += x * x - old * old;
        if (++since_recompute_ >= 4 * w) {
            s1_ = s2_ = 0;
            for (double v : ring_) {
                s1_ += v;
                s2_ += v * v;
            }
            since_recompute_ = 0;
        }
    }
    bool still = false;
    double mean = 0;
    if (count_ == w) {
        const double n = static_cast<double>(w);
        mean = s1_ / n;
        const double var = std::max(0.0, (s2_ - n * mean * mean) / (n - 1));
        still = std::sqrt(var) <= settings_.plateau_std_mm;
    }
    bool started = false;
    if (still && in_plateau_ &&
        std::abs(mean - level_sum_ / static_cast<double>(level_n_)) > settings_.plateau_level_mm) {
        close_plateau();
        if (held_) return void_measurement("the bar's level changed after the window (the machine moved)");
    }
    if (still) {
        if (!in_plateau_) {
            in_plateau_ = true;
            started = true;
            level_sum_ = 0;
            level_n_ = 0;
            plateau_start_us_ = ring_time_[head_];  // the window's first sample
        }
        level_sum_ += x;
        ++level_n_;
        plateau_last_us_ = t;
    } else if (in_plateau_) {
        const bool was_measuring = measuring_.has_value();
        close_plateau();
        if (was_measuring && held_)
            return void_measurement("the machine moved within " + seconds(t - held_->last_time_us) +
                                    " of the window's end (the window may hold the start of the move)");
        if (was_measuring) return void_measurement("the machine moved before the window was averaged");
    }

    // A measuring plateau directly after a complete code: the named point's dwell.
    if (started && !measuring_ && std::abs(mean) <= settings_.measuring_level_mm) {
        const std::size_t expected_digits = static_cast<std::size_t>(data_digits_) + 1;
        if (tags_.size() == expected_digits) {
            // The digits, read relative to this dwell's level.
            digits_.clear();
            bool misread = false;
            for (std::size_t k = 0; k < tags_.size(); ++k) {
                const auto d = tag_digit(settings_.code, static_cast<int>(k), tags_[k] - mean);
                if (!d) {
                    misread = true;
                    break;
                }
                digits_.push_back(*d);
            }
            const auto point = misread ? std::nullopt : decode_point(digits_);
            if (!point || *point >= settings_.point_count) {
                ev.kind = AttributionEvent::Kind::Void;
                ev.evidence = "code " + digits_text() + " at " + seconds(code_start_us_) +
                              (misread ? " has a tag at no tag length"
                               : point ? " names no point of the plan"
                                       : " fails its check digit");
            } else {
                measuring_ = point;
                measuring_start_us_ = plateau_start_us_;
                measuring_evidence_ = "code " + digits_text() + " read from " + seconds(code_start_us_) + " to " +
                                      seconds(plateau_start_us_);
                detector_.reset(true);
                if (*point < expected_mm_.size()) detector_.set_expected(expected_mm_[*point]);
            }
        } else if (!tags_.empty()) {
            ev.kind = AttributionEvent::Kind::Void;
            ev.evidence = "code " + digits_text() + "… incomplete before the dwell at " + seconds(plateau_start_us_);
        }
        digits_.clear();
        tags_.clear();
    }
    const auto confirm_us = static_cast<std::uint64_t>(std::llround(settings_.confirm_s * 1e6));
    if (measuring_ && !held_ && detector_.push(s) == DwellDetector::Result::Captured) {
        held_ = detector_.stats();
        // The program's timing: the machine leaves when the G4 ends, seen in the bar or not.
        const auto dwell_us = static_cast<std::uint64_t>(std::llround(settings_.measuring_dwell_s * 1e6));
        if (dwell_us > 0 && held_->last_time_us + confirm_us > measuring_start_us_ + dwell_us)
            return void_measurement("the window ends " + seconds(held_->last_time_us - measuring_start_us_) +
                                    " into a dwell of " + seconds(dwell_us) +
                                    ", too close to its end (the machine leaves when its G4 ends)");
    }
    if (measuring_ && held_ && t >= held_->last_time_us + confirm_us) {
        // Still at the same level for confirm_s after the window (no gap, no move): the evidence holds.
        ev.kind = AttributionEvent::Kind::Captured;
        ev.point = measuring_;
        ev.stats = *held_;
        ev.evidence = measuring_evidence_ + "; window " + seconds(ev.stats.first_time_us) + " to " +
                      seconds(ev.stats.last_time_us) + ", the bar still " + seconds(t - ev.stats.last_time_us) +
                      " after it";
        measuring_.reset();
        held_.reset();
    }
    return ev;
}

}  // namespace ballbar::acquisition
