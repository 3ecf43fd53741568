// SPDX-License-Identifier: MIT
// The sample spacing a circular test needs (circular.hpp, sampling_limit; docs/circular.md).
#include <algorithm>

#include "ballbar/analysis/circular.hpp"

namespace ballbar::analysis::circular {

SamplingLimit sampling_limit(const TestSpec& test, double sample_rate_hz, const AnalysisOptions& options) {
    SamplingLimit l;
    const double pitch_spacing = options.min_pitch_mm / kSamplesPerMinPitch;
    const double feed_in_spacing = test.feed_in_mm / kSamplesPerFeedIn;
    l.max_spacing_mm = std::min(pitch_spacing, feed_in_spacing);
    l.binding = feed_in_spacing < pitch_spacing ? "feed-in" : "cyclic-error pitch";
    l.max_feed_mm_min = sample_rate_hz > 0.0 ? 60.0 * sample_rate_hz * l.max_spacing_mm : 0.0;
    return l;
}

}  // namespace ballbar::analysis::circular
