// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "ballbar/acquisition/dwell.hpp"

namespace ballbar::acquisition {
namespace {

using analysis::BarSample;

constexpr double kL = 100.0;

class Stream {
  public:
    /// `n` samples at length `mm` (+ slope mm/sample) with Gaussian noise.
    void add(std::size_t n, double mm, double slope = 0, double noise_mm = 0.0002, std::uint16_t flags = 0) {
        for (std::size_t i = 0; i < n; ++i) {
            BarSample s;
            s.seq = seq_++;
            s.device_time_us = s.seq * 1000;
            s.displacement_nm = static_cast<std::int32_t>(
                std::lround((mm + slope * static_cast<double>(i) + noise_(rng_) * noise_mm - kL) * 1e6));
            s.flags = flags;
            samples.push_back(s);
        }
    }
    std::vector<BarSample> samples;

  private:
    std::uint64_t seq_ = 0;
    std::mt19937_64 rng_{3};
    std::normal_distribution<double> noise_{0, 1};
};

struct Outcome {
    std::vector<std::size_t> settled;
    std::vector<WindowStats> captured;
};

Outcome feed(DwellDetector& d, const std::vector<BarSample>& s) {
    Outcome o;
    for (std::size_t i = 0; i < s.size(); ++i) {
        const auto r = d.push(s[i]);
        if (r == DwellDetector::Result::Settled) o.settled.push_back(i);
        if (r == DwellDetector::Result::Captured) o.captured.push_back(d.stats());
    }
    return o;
}

DwellSettings settings() {
    DwellSettings s;
    s.window = 200;
    s.calibrated_length_mm = kL;
    return s;
}

TEST(Dwell, CapturesAFreshWindowAfterTheBarSettles) {
    Stream st;
    st.add(300, kL - 0.2, 0.001);  // moving: 1 µm per sample
    st.add(1000, kL + 0.0123);     // dwell
    DwellDetector d(settings());
    d.set_expected(kL);
    const Outcome o = feed(d, st.samples);
    ASSERT_EQ(o.captured.size(), 1u);  // one point per dwell, however long
    const WindowStats& w = o.captured[0];
    EXPECT_NEAR(w.mean_mm, kL + 0.0123, 0.0001);
    EXPECT_EQ(w.n, 200u);
    // The averaged window holds no moving sample and starts about a window after the bar stopped.
    EXPECT_GE(w.first_seq, 300u + 150u);
    EXPECT_EQ(w.last_seq - w.first_seq + 1, 200u);
    EXPECT_LT(std::abs(w.drift_mm), 0.0002);
    EXPECT_NEAR(w.std_mm, 0.0002, 0.00005);
}

TEST(Dwell, NeedsMotionBetweenTwoPointsAtTheSameLength) {
    Stream st;
    st.add(600, kL + 0.01);
    st.add(400, kL + 0.01, 0.002);  // the machine moves on
    st.add(600, kL - 0.02);
    DwellDetector d(settings());
    d.set_expected(kL);
    const Outcome o = feed(d, st.samples);
    ASSERT_EQ(o.captured.size(), 2u);
    EXPECT_NEAR(o.captured[0].mean_mm, kL + 0.01, 1e-4);
    EXPECT_NEAR(o.captured[1].mean_mm, kL - 0.02, 1e-4);
}

TEST(Dwell, StillBarAtTheWrongLengthIsNotAPoint) {
    Stream st;
    st.add(1000, kL + 0.7);  // outside the 0.5 mm tolerance
    DwellDetector d(settings());
    d.set_expected(kL);
    EXPECT_TRUE(feed(d, st.samples).captured.empty());
}

TEST(Dwell, SlowDriftIsNotStill) {
    Stream st;
    st.add(2000, kL, 0.0001);  // 0.1 µm/sample: 20 µm across a window
    DwellDetector d(settings());
    d.set_expected(kL);
    EXPECT_TRUE(feed(d, st.samples).captured.empty());
}

TEST(Dwell, OutOfRangeSampleVoidsTheWindow) {
    Stream st;
    st.add(300, kL);
    st.add(1, kL + 1.0, 0, 0, analysis::kSampleOutOfRange);
    st.add(150, kL);
    DwellDetector d(settings());
    d.set_expected(kL);
    const Outcome o = feed(d, st.samples);
    // 300 still samples settle at 199 and start a window; the flagged sample voids it; 150 are too few.
    EXPECT_EQ(o.settled.size(), 1u);
    EXPECT_TRUE(o.captured.empty());
}

// A sample without a bar temperature (a gauge's, or a failed sensor's) voids nothing: the window is
// captured unflagged, and its temperature is the mean of the samples that have one, or none at all.
TEST(Dwell, SamplesWithoutABarTemperatureAreCapturedAndGiveNoTemperature) {
    Stream none;
    none.add(1000, kL + 0.0123, 0, 0.0002, analysis::kSampleTempInvalid);
    DwellDetector d(settings());
    d.set_expected(kL);
    Outcome o = feed(d, none.samples);
    ASSERT_EQ(o.captured.size(), 1u);
    EXPECT_FALSE(o.captured[0].flagged);
    EXPECT_FALSE(o.captured[0].bar_temp_C.has_value());

    Stream some;
    some.add(1000, kL + 0.0123);
    for (std::size_t i = 0; i < some.samples.size(); ++i) {
        some.samples[i].bar_temp_C = i % 2 ? 21.5f : 99.0f;  // the invalid ones carry nonsense
        if (i % 2 == 0) some.samples[i].flags = analysis::kSampleTempInvalid;
    }
    DwellDetector d2(settings());
    d2.set_expected(kL);
    o = feed(d2, some.samples);
    ASSERT_EQ(o.captured.size(), 1u);
    ASSERT_TRUE(o.captured[0].bar_temp_C.has_value());
    EXPECT_DOUBLE_EQ(*o.captured[0].bar_temp_C, 21.5);

    Stream unreferenced;
    unreferenced.add(1000, kL + 0.0123, 0, 0.0002, analysis::kSampleNotReferenced);
    DwellDetector d3(settings());
    d3.set_expected(kL);
    o = feed(d3, unreferenced.samples);
    ASSERT_EQ(o.captured.size(), 1u);
    EXPECT_TRUE(o.captured[0].flagged);
}

TEST(Dwell, ManualCaptureTakesTheNextWindow) {
    Stream st;
    st.add(250, kL + 0.3, 0.0);
    DwellDetector d(settings());
    d.set_expected(kL);
    d.capture_now();
    const Outcome o = feed(d, st.samples);
    ASSERT_EQ(o.captured.size(), 1u);
    EXPECT_EQ(o.captured[0].first_seq, 0u);
    EXPECT_NEAR(o.captured[0].mean_mm, kL + 0.3, 1e-4);
}

TEST(Dwell, RunningSumsStayExactOverLongStreams) {
    Stream st;
    for (int k = 0; k < 50; ++k) {
        st.add(900, kL + 0.001 * k);
        st.add(300, kL + 0.001 * k, 0.001);
    }
    DwellDetector d(settings());
    d.set_expected(kL);
    const Outcome o = feed(d, st.samples);
    ASSERT_EQ(o.captured.size(), 50u);
    for (int k = 0; k < 50; ++k) EXPECT_NEAR(o.captured[static_cast<std::size_t>(k)].mean_mm, kL + 0.001 * k, 1e-4);
}

}  // namespace
}  // namespace ballbar::acquisition
