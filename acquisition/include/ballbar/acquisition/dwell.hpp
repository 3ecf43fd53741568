// SPDX-License-Identifier: MIT
// Dwell detection in the live bar stream: the bar is still (low standard deviation and drift over a
// sliding window) and reads the planned point's expected length within a tolerance. Once still, a fresh
// window is averaged (so the end of the approach move never enters a point). After a point has been
// taken, the detector waits for the bar to move before it looks for the next one.
//
// Fixed memory: the window is a ring buffer allocated once; statistics are running sums (recomputed
// exactly once per window to keep rounding from accumulating over long sessions).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "ballbar/analysis/sample.hpp"

namespace ballbar::acquisition {

struct DwellSettings {
    std::size_t window = 500;  ///< samples per window
    /// The window's length in device time (0: by count only). A captured window ends when it holds
    /// `window` samples or spans this long with at least half of them: frames lost on the link then
    /// thin the window instead of stretching it towards the end of the dwell (issue 24).
    double window_s = 0;
    double still_std_mm = 0.008;    ///< "still": standard deviation at most this
    double still_drift_mm = 0.008;  ///< "still": |fitted slope × window| at most this
    double tolerance_mm = 0.5;      ///< |mean − expected| at most this
    double calibrated_length_mm = 100;
};

/// Statistics of one averaged window.
struct WindowStats {
    double mean_mm = 0;   ///< bar length
    double std_mm = 0;    ///< sample standard deviation
    double drift_mm = 0;  ///< fitted slope × (window − 1) samples
    std::size_t n = 0;
    std::uint64_t first_seq = 0, last_seq = 0;
    std::uint64_t first_time_us = 0, last_time_us = 0;
    /// Mean over the window's samples that carry one (no kSampleTempInvalid); empty when none does.
    std::optional<double> bar_temp_C;
    /// A sample had a flag that voids the window: not referenced, or the first after a gap. Out of
    /// range voids it another way (the window restarts); no bar temperature voids nothing.
    bool flagged = false;
};

class DwellDetector {
  public:
    enum class Result { None, Settled, Captured };

    explicit DwellDetector(const DwellSettings& settings);

    /// The length the next point should read.
    void set_expected(double expected_mm) { expected_mm_ = expected_mm; }
    /// Forget the window (after a disconnect or a rejected point); `armed` says whether a still bar
    /// may be taken at once (true) or only after it moved (false).
    void reset(bool armed);
    /// Skip the search: capture the next window at once (manual mode, the operator confirmed).
    void capture_now();

    /// Feeds one sample. Settled: a still window at the expected length was found and the averaging
    /// window starts. Captured: `stats()` holds the averaged window; the detector then waits for motion.
    Result push(const analysis::BarSample& s);
    const WindowStats& stats() const { return stats_; }
    /// Statistics of the current (possibly partial) window: the live reading.
    double last_length_mm() const { return last_mm_; }
    bool capturing() const { return mode_ == Mode::Capturing; }
    /// How full the averaging window is (0 while searching).
    double fill() const {
        return mode_ == Mode::Capturing ? static_cast<double>(count_) / static_cast<double>(ring_.size()) : 0.0;
    }

  private:
    enum class Mode { Searching, Capturing };
    void clear();
    void add(double x, const analysis::BarSample& s);
    void recompute();
    void compute(WindowStats& out) const;

    DwellSettings settings_;
    std::vector<double> ring_;  ///< deviations from expected, mm
    std::size_t head_ = 0, count_ = 0, since_recompute_ = 0;
    double s1_ = 0, s2_ = 0, sxt_ = 0;  ///< Σx, Σx², Σk·x (k = position in the window)
    double temp_sum_ = 0;               ///< Σ bar temperature over the samples that carry one
    std::size_t temp_n_ = 0;            ///< how many do
    std::uint64_t first_seq_ = 0, first_time_ = 0, last_seq_ = 0, last_time_ = 0;
    bool flagged_ = false;
    double expected_mm_ = 0;
    double last_mm_ = 0;
    bool armed_ = true;
    Mode mode_ = Mode::Searching;
    WindowStats stats_;
};

}  // namespace ballbar::acquisition
