// SPDX-License-Identifier: MIT
// The circular test of ISO 230-4 on a ball-bar trace (docs/circular.md, format docs/formats/trace.md).
//
// A trace holds bar lengths over time and the test's specification, never angles. `analyze_circular`
// finds each run's feed-in in the data (a fall of feed_in_mm at the programmed feed, fitted as a
// ramp through a first-order servo lag), takes the commanded angle from time and feed after it, and
// computes the ISO 230-4 figures (G per run, G(b), F) and the diagnostics: a least-squares fit of
// every effect's radial signature, with standard uncertainties from the residual, a ranked share of
// the circular deviation, and the effects this data cannot separate reported as such.
//
// Pure computation: no I/O, no clocks. Errors in the data (no feed-in found, trace too short) throw
// `CircularError` naming the run and the problem.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace ballbar::analysis::circular {

enum class Plane { XY, YZ, ZX };
enum class Direction { Ccw, Cw };

/// "XY", "YZ", "ZX" / "ccw", "cw"; the parsers return nullopt on anything else.
const char* plane_name(Plane plane);
std::optional<Plane> parse_plane(const std::string& text);
const char* direction_name(Direction direction);
std::optional<Direction> parse_direction(const std::string& text);
/// Machine axis letters of the plane's p and q axes, lower case ('x', 'y') for XY.
std::array<char, 2> plane_axes(Plane plane);
/// Index (0 = X, 1 = Y, 2 = Z) of the plane's p and q axes in machine coordinates.
std::array<int, 2> plane_axis_index(Plane plane);

struct RunSpec {
    Direction direction = Direction::Ccw;
    double start_deg = 0.0;
    double overshoot_deg = 45.0;
    double data_arc_deg = 360.0;
};

/// The `test` header of a ballbar-trace/1 file.
struct TestSpec {
    Plane plane = Plane::XY;
    double radius_mm = 100.0;
    std::array<double, 3> centre_mm{0.0, 0.0, 0.0};
    double feed_mm_min = 1000.0;
    double feed_in_mm = 1.5;
    std::vector<RunSpec> runs;

    /// Empty when usable, else what is wrong ("radius_mm must be > 0").
    std::string validate() const;
};

struct TraceSample {
    double time_s = 0.0;
    double measured_mm = 0.0;
};

class CircularError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// Every diagnostic of the format; `diagnostic_key` gives its JSON key for a plane.
enum class Diag {
    BacklashP,
    BacklashQ,
    SpikeP,
    SpikeQ,
    Squareness,
    ScaleMismatch,
    ServoMismatch,
    CyclicP,
    CyclicPitchP,
    CyclicQ,
    CyclicPitchQ,
    StraightnessP,
    StraightnessQ,
    Vibration,
    VibrationHz,
};
inline constexpr int kDiagCount = 15;
std::string diagnostic_key(Diag diag, Plane plane);
/// The diagnostic's unit as docs/cli.md's JSON vocabulary names it: "um", "um_per_m", "ppm", "ms",
/// "mm", "hz".
const char* diagnostic_unit(Diag diag);
/// The same for the screen: "µm", "µm/m", "ppm", "ms", "mm", "Hz".
const char* diagnostic_unit_symbol(Diag diag);
/// Radial deviation (µm, peak) that one unit of the diagnostic causes in this test: the scale on
/// which "an equivalent radial amplitude" is judged. 0 for pitch and frequency.
double radial_um_per_unit(Diag diag, const TestSpec& test);

struct RunResult {
    Direction direction = Direction::Ccw;
    double feed_in_end_s = 0.0;  ///< commanded end of the feed-in, found in the data
    double servo_lag_s = 0.0;    ///< first-order lag of the feed-in's motion, found in the data
    double data_start_s = 0.0;   ///< time the data arc starts and ends
    double data_end_s = 0.0;
    std::size_t first_sample = 0;  ///< samples [first, last) of the trace are the data arc
    std::size_t last_sample = 0;
    double circularity_um = 0.0;  ///< G: least-squares centre, max − min radial deviation
    double radial_max_um = 0.0;   ///< F over this run: measured − programmed radius
    double radial_min_um = 0.0;
    /// The diagnosed model's curve over the data arc, for the polar plot's overlay: what the fit explains
    /// (every diagnosis, the lag and the centre; not the vibration, which is of time, not of the path)
    /// less one least-squares circle fitted to it over every run
    /// (the reference of G(b) and of the plot), reduced to its min and max per `kModelCurveStep_deg` of the
    /// arc (in the order they occur). `model_arc_deg`: the commanded angle travelled since the data arc
    /// began; the samples within a few ms of an axis reversal, which the diagnosis leaves out, are absent.
    std::vector<double> model_arc_deg;
    std::vector<double> model_deviation_um;
};
inline constexpr double kModelCurveStep_deg = 0.5;

struct DiagnosticResult {
    Diag diag = Diag::BacklashP;
    std::string key;
    double value = 0.0;
    double std_uncertainty = 0.0;
    bool detected = true;          ///< cyclic error and vibration: a significant peak was found
    double share_percent = 0.0;    ///< of the sum of all diagnostics' peak-to-valley contributions
    double contribution_um = 0.0;  ///< peak-to-valley of this effect's radial signature over the data
};

/// Effects whose radial signatures coincide on this data: only their combination is known.
struct UnseparableGroup {
    std::vector<std::string> keys;  ///< diagnostic keys (and "centre" for the set-up offset)
    std::string reason;
    std::string combined_key;     ///< the fit's column that carries the combination (may be empty)
    double combined_value = 0.0;  ///< in combined_key's unit
    double combined_std = 0.0;
};

struct CircularResult {
    TestSpec test;
    std::vector<RunResult> runs;
    std::optional<double> bidirectional_um;  ///< G(b): both directions present
    /// H, circular hysteresis (ISO 230-4): the largest radial difference between the clockwise and the
    /// counter-clockwise path, compared in 1° sectors about G(b)'s centre; both directions present.
    std::optional<double> hysteresis_um;
    double radial_max_um = 0.0;  ///< F: max and min over every data arc
    double radial_min_um = 0.0;
    std::vector<DiagnosticResult> diagnostics;  ///< separable ones, ranked by share (largest first)
    std::vector<UnseparableGroup> unseparable;
    double residual_rms_um = 0.0;  ///< after removing the centre and every diagnosis
    double mean_radius_um = 0.0;   ///< fitted mean of measured − programmed radius
    double mean_radius_std_um = 0.0;
    std::size_t samples_used = 0;
    double sample_rate_hz = 0.0;

    const DiagnosticResult* find(Diag diag) const;
};

struct AnalysisOptions {
    double min_pitch_mm = 2.0;       ///< cyclic error searched from here to radius / 4
    double min_vibration_hz = 2.0;   ///< vibration searched from here to 0.45 × sample rate
    double min_independence = 0.05;  ///< below this a signature counts as not separable
    /// The longest time without samples a run may have, from its feed-in to the end of its data arc
    /// (at least 3 sample periods). A longer hole, or a jump of the clock, leaves angles unmeasured or
    /// misplaced (every later angle comes from time): the analysis refuses the run and names the hole.
    /// The same bound as the live session's (acquisition's CircularOptions::max_gap_s).
    double max_hole_s = 0.050;
};

/// How coarsely a test may be sampled (docs/circular.md, "Sample spacing"). Samples lie F / (60 · rate)
/// mm apart along the path at feed F. The diagnosis needs (1) two samples per shortest cyclic-error
/// pitch it searches (`min_pitch_mm`: the sampling theorem along an axis, which never moves faster than
/// the path) and (2) three samples on each radial feed-in (`feed_in_mm` at the feed), which the run
/// finder fits with a three-parameter lagged ramp to find where the data arc starts.
struct SamplingLimit {
    double max_spacing_mm = 0.0;   ///< the coarsest usable spacing along the path
    double max_feed_mm_min = 0.0;  ///< the highest usable feed at the rate
    const char* binding = "";      ///< which need sets it: "cyclic-error pitch" or "feed-in"
};
inline constexpr double kSamplesPerMinPitch = 2.0;
inline constexpr double kSamplesPerFeedIn = 3.0;
/// The limit for `test` (its feed-in) at `sample_rate_hz` (> 0).
SamplingLimit sampling_limit(const TestSpec& test, double sample_rate_hz, const AnalysisOptions& options = {});

/// The whole analysis. Samples in time order (strictly increasing). Throws CircularError.
CircularResult analyze_circular(const TestSpec& test, const std::vector<TraceSample>& samples,
                                const AnalysisOptions& options = {});

/// Where a run's data arc lies in a trace, found from its feed-in (exposed for the acquisition's
/// live run finder and for tests). `from` is the first sample to search.
struct FeedIn {
    double command_end_s = 0.0;  ///< commanded end of the radial move
    double lag_s = 0.0;          ///< fitted first-order lag of the move
    double standing_mm = 0.0;    ///< bar length before the move
    std::size_t index = 0;       ///< first sample after the move's half-way point
};
std::optional<FeedIn> find_feed_in(const TestSpec& test, const std::vector<TraceSample>& samples, std::size_t from);

// ---- volumetric: an XY full circle with YZ and ZX (partial) arcs ----

struct VolumetricFigure {
    std::string key;  ///< squareness_xy_um_per_m, backlash_x_um, scale_x_ppm, ...
    double value = 0.0;
    double std_uncertainty = 0.0;
    bool known = false;  ///< false when no plane determined it
};

struct VolumetricResult {
    std::vector<VolumetricFigure> figures;  ///< 3 squareness, 3 backlash, 3 scale
};

/// Combines one result per plane (any order; each plane at most once). Squareness per plane as
/// measured; backlash of an axis is the uncertainty-weighted mean of the planes that contain it;
/// the axes' scale errors from the three mismatches and the planes' mean radius (the bar length is
/// absolute, so (s_p + s_q)/2 = mean radius offset / R), by weighted least squares.
VolumetricResult combine_volumetric(const std::vector<CircularResult>& planes);

}  // namespace ballbar::analysis::circular
