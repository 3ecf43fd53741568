// SPDX-License-Identifier: MIT
// Attribution of dwells to planned points from evidence in the bar stream. The NC program writes each
// point's code into the bar length before its measuring dwell (point_code.hpp); this reader segments
// the stream into *plateaus* (the bar still over a short window), reads the code from the tag plateaus
// that directly precede a plateau at the measuring length, checks the code's check digit and the tag
// dwells' durations against the program's G4 times, and only then averages a window of that dwell
// (DwellDetector) as the named point. A gap in the stream longer than `max_gap_s`, a reconnect, a
// missing or misread tag, or motion before the window is full makes the dwell *void*: it is reported,
// never stored as a point (docs/procedure.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ballbar/acquisition/dwell.hpp"
#include "ballbar/acquisition/point_code.hpp"
#include "ballbar/analysis/sample.hpp"

namespace ballbar::acquisition {

struct AttributionSettings {
    PointCodeSpec code;
    std::size_t point_count = 0;  ///< points of the plan (codes name plan indices)
    double sample_rate_hz = 1000;
    double bar_length_mm = 100;       ///< the plan's bar length (the measuring level)
    double plateau_window_s = 0.05;   ///< window of the plateau detector
    double plateau_std_mm = 0.008;    ///< still: standard deviation over that window at most this
    double plateau_level_mm = 0.03;   ///< a plateau's samples stay this close to its level
    double measuring_level_mm = 0.3;  ///< |level − bar length| of a measuring dwell at most this
    DwellSettings dwell;              ///< the averaging of the attributed dwell
    /// The program's G4 at each measuring point (0: unknown). A window must end this long after its
    /// dwell began, less `confirm_s`, at the latest: the machine leaves the point when the G4 ends,
    /// whether or not the bar length shows it (a move across the bar changes its length little).
    double measuring_dwell_s = 0;
    /// A window counts only once the bar has stood still at the same level this long after its last
    /// sample: a move that began within the window shows by then (the plateau detector needs at most
    /// its own window to see one). Until then the point is held, not captured.
    double confirm_s = 0.1;
};

/// What one pushed sample concluded.
struct AttributionEvent {
    enum class Kind { None, Captured, Void };
    Kind kind = Kind::None;
    std::optional<std::size_t> point;  ///< Captured: the point the code named; Void: when known
    WindowStats stats;                 ///< Captured: the averaged window
    std::string evidence;              ///< "code 0121 read at 12.345 s" / why it is void
};

class DwellAttributor {
  public:
    explicit DwellAttributor(const AttributionSettings& settings);

    /// Feeds one sample (repeats already dropped; gaps are seen from the device time).
    AttributionEvent push(const analysis::BarSample& s);
    /// Forget everything (after a reconnect: the stream before it is no evidence for what follows).
    /// Returns a Void event when a dwell was being averaged or a code was being read.
    AttributionEvent reset(const std::string& why);
    /// The expected length of each point (all the plan's points).
    void set_expected(std::vector<double> expected_mm) { expected_mm_ = std::move(expected_mm); }
    double last_length_mm() const { return last_mm_; }
    /// 0..1 of the window being averaged (0 while no dwell is attributed).
    double fill() const { return measuring_ ? detector_.fill() : 0.0; }
    /// The point whose dwell is being averaged.
    std::optional<std::size_t> measuring() const { return measuring_; }

  private:
    void close_plateau();
    AttributionEvent void_measurement(const std::string& why);
    std::string digits_text() const;

    AttributionSettings settings_;
    int data_digits_;
    std::vector<double> expected_mm_;
    // Plateau detector: a ring of deviations from the bar length and running sums.
    std::vector<double> ring_;
    std::size_t head_ = 0, count_ = 0, since_recompute_ = 0;
    double s1_ = 0, s2_ = 0;
    std::vector<std::uint64_t> ring_time_;
    bool in_plateau_ = false;
    double level_sum_ = 0;
    std::size_t level_n_ = 0;
    std::uint64_t plateau_start_us_ = 0, plateau_last_us_ = 0;
    std::optional<std::uint64_t> last_time_us_;
    // The code being read and the dwell being averaged.
    std::vector<double> tags_;  ///< levels of the tag plateaus read so far
    std::vector<int> digits_;
    std::uint64_t code_start_us_ = 0;
    std::optional<std::size_t> measuring_;
    std::string measuring_evidence_;
    std::uint64_t measuring_start_us_ = 0;  ///< the measuring dwell's plateau began here
    std::optional<WindowStats> held_;       ///< averaged, waiting for the stillness after it
    DwellDetector detector_;
    double last_mm_ = 0;
};

}  // namespace ballbar::acquisition
