// SPDX-License-Identifier: MIT
#include "ballbar/acquisition/point_code.hpp"

#include <algorithm>
#include <cmath>

namespace ballbar::acquisition {

namespace {
constexpr int kBase = 3;
constexpr int kLevels = 3;

int check_digit(std::span<const int> data) {
    // Weighted sum mod 3 with weights 1, 2, 1, 2, ...: any single changed digit changes it.
    int sum = 0;
    for (std::size_t i = 0; i < data.size(); ++i) sum += data[i] * (i % 2 == 0 ? 1 : 2);
    return sum % kBase;
}
}  // namespace

int code_data_digits(std::size_t point_count) {
    int d = 2;
    std::size_t capacity = kBase * kBase;
    while (capacity < point_count) {
        capacity *= kBase;
        ++d;
    }
    return d;
}

std::vector<int> encode_point(std::size_t index, int data_digits) {
    std::vector<int> digits(static_cast<std::size_t>(data_digits));
    for (int i = data_digits - 1; i >= 0; --i) {
        digits[static_cast<std::size_t>(i)] = static_cast<int>(index % kBase);
        index /= kBase;
    }
    digits.push_back(check_digit(digits));
    return digits;
}

std::optional<std::size_t> decode_point(std::span<const int> digits) {
    if (digits.size() < 3) return std::nullopt;
    const auto data = digits.first(digits.size() - 1);
    if (check_digit(data) != digits.back()) return std::nullopt;
    std::size_t index = 0;
    for (int d : data) {
        if (d < 0 || d >= kBase) return std::nullopt;
        index = index * kBase + static_cast<std::size_t>(d);
    }
    return index;
}

double tag_offset_mm(const PointCodeSpec& spec, int position, int digit) {
    const double magnitude = spec.min_offset_mm + spec.digit_step_mm * digit;
    return position % 2 == 0 ? -magnitude : magnitude;
}

std::optional<int> tag_digit(const PointCodeSpec& spec, int position, double offset_mm) {
    for (int d = 0; d < kLevels; ++d)
        if (std::abs(offset_mm - tag_offset_mm(spec, position, d)) <= spec.decision_mm) return d;
    return std::nullopt;
}

PointCodeSpec code_for_rate(double sample_rate_hz) {
    PointCodeSpec c;
    if (!(sample_rate_hz > 0)) return c;
    const double period_s = 1.0 / sample_rate_hz;
    c.tag_dwell_s = std::max(c.tag_dwell_s, 10 * period_s);
    c.min_plateau_s = std::max(c.min_plateau_s, 0.5 * c.tag_dwell_s);
    c.max_plateau_s = std::max(c.max_plateau_s, 3 * c.tag_dwell_s);
    c.max_gap_s = std::max(c.max_gap_s, 2.5 * period_s);
    return c;
}

}  // namespace ballbar::acquisition
