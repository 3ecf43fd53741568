// SPDX-License-Identifier: MIT
// The content of a session report: everything the PDF shows, as plain data. `build_report` (build.hpp)
// fills it from the database; `render_pdf` draws it on A4 pages; `to_json` writes the same content as data
// (docs/report.md describes the schema).
//
// Units are in the names: lengths in mm or µm, angles in radians (the report shows degrees and
// arcseconds), times in seconds since the session started.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "ballbar/analysis/types.hpp"

namespace ballbar::report {

using analysis::Vec3;

/// Thrown when a report cannot be produced (unwritable file, inconsistent content).
class ReportError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// Smallest, mean and largest value of a quantity over the session; empty when never measured.
struct Range {
    std::optional<double> min, mean, max;
    bool present() const { return mean.has_value(); }
};

struct Header {
    std::int64_t session_id = 0;
    std::string session_name;
    std::string status;       ///< the session's state at the end (completed, interrupted, …)
    std::string started_at;   ///< ISO 8601
    std::string finished_at;  ///< ISO 8601; empty while running or when unknown
    analysis::MachineGeometry machine;
    std::string instrument_model, instrument_serial, instrument_firmware, instrument_calibration_date;
    std::optional<double> calibrated_length_mm;
    std::string operator_name;
    Range bar_temp_C, machine_temp_C, air_temp_C;
    std::string software_version;
    std::string notes;
};

/// One entry of the procedure as it was followed (a state transition of the guided procedure).
struct ProcedureEvent {
    double time_s = 0;      ///< since the session started
    std::string timestamp;  ///< ISO 8601 wall clock; may be empty
    std::string kind;       ///< "step", "repeat", "pause", "resume", "abort", "finish" or another word
    std::string step;       ///< the step (state) entered
    std::string detail;     ///< free text: why repeated, which point, …
};

/// Total position error ΔV of one SSM location, machine frame.
struct LocationError {
    int location = 0;
    std::string label;                        ///< e.g. "before rotation", "A=90° C=0°"
    Vec3 position_mm = Vec3::Zero();          ///< where the tool ball was (for the to-scale vector plots)
    Vec3 error_um = Vec3::Zero();             ///< Δx, Δy, Δz
    Vec3 uncertainty_um = Vec3::Constant(0);  ///< standard uncertainty of each component (k = 1)
    int points = 0;                           ///< readings the solution used
    std::optional<double> residual_rms_um;    ///< of the bar lengths after the solution
    std::optional<double> condition;          ///< condition number of the layout
};

/// An orientation error of a rotary axis, from two locations (first-order model and exact inversion).
struct OrientationError {
    std::string symbol;                        ///< "Δα", "Δβ", "Δγ"
    std::string axis;                          ///< "A", "B", "C"
    std::optional<double> commanded_rad;       ///< the commanded angle of the axis at the measurement
    std::optional<double> first_order_rad;     ///< the seed's first-order equation (corrected)
    std::optional<double> exact_rad;           ///< exact nonlinear inversion
    std::optional<double> uncertainty_rad;     ///< standard uncertainty of the exact value
    int from_location = -1, to_location = -1;  ///< the two locations it was computed from
};

/// A time window in which the procedure averaged samples into a point.
struct CaptureWindow {
    double start_s = 0, end_s = 0;
    int location = -1, point = -1;
    std::optional<double> mean_um;  ///< averaged displacement in the window
};

/// The bar reading over time, already reduced for plotting (min/max per column, extremes kept;
/// see decimate.hpp). `samples` is how many raw samples it stands for.
struct BarTrace {
    std::vector<double> time_s;
    std::vector<double> displacement_um;  ///< transducer displacement from the calibrated length
    std::uint64_t samples = 0;
    std::optional<double> min_um, max_um;  ///< over every raw sample (not only the kept ones)
    std::size_t gaps = 0;                  ///< gaps in the stream the session recorded (schema v6)
    double gap_s = 0;                      ///< their instrument time in all (reconnects count 0)
};

/// One parameter of an identified error model.
struct ModelParameter {
    std::string name;  ///< ISO symbol or ours ("X0C", "A_zero")
    std::string unit;  ///< unit of value and uncertainty as shown ("µm", "arcsec", "µm/m", …)
    double value = 0;
    std::optional<double> uncertainty;    ///< standard uncertainty, same unit
    std::optional<double> observability;  ///< 0..1 (1: fully determined by the measured layout)
    std::string note;                     ///< e.g. "fixed", "poorly observable"
};

struct IdentifiedModel {
    std::string name;  ///< e.g. "rotary location errors (TTTRR)"
    std::vector<ModelParameter> parameters;
    std::optional<bool> converged;
    std::optional<int> iterations;
    std::optional<double> residual_rms_before_um, residual_rms_after_um;
    std::optional<double> condition;
};

/// One step of the discovery workflow: the residuals against the variable that explains them, before
/// and after adding the effect.
struct DiscoveryStep {
    std::string effect;                       ///< e.g. "spindle growth"
    std::string variable;                     ///< the explaining variable, e.g. "session time"
    std::string variable_unit;                ///< e.g. "min"
    std::vector<double> x;                    ///< the variable at each reading
    std::vector<double> before_um, after_um;  ///< residuals at each reading (same length as x)
    std::optional<double> rms_before_um, rms_after_um;
    std::optional<bool> accepted;
    bool binned = false;    ///< before/after are binned means (8 quantile bins of the variable)
    bool own_step = false;  ///< binned: of this step's residuals before and after it (else the whole
                            ///< workflow's first and last, as results stored before step trends were)
    std::string note;
    std::string y_label, y_unit;  ///< the plotted quantity; empty: the residual in µm
};

/// Before/after of compensation for one axis (a bar per axis in the figure).
struct CompensationAxis {
    std::string axis;  ///< "X", "Y", "Z", "A", "C", …
    std::string unit;  ///< "µm" or "arcsec"
    double before = 0, after = 0;
};

/// One run of a circular test: its ISO figures, where its data arc lies in time, and its samples on the
/// polar plot (min/max per angle column, like the bar-reading figure).
struct CircularRun {
    std::string direction;  ///< "ccw" or "cw"
    double start_deg = 0, overshoot_deg = 0, data_arc_deg = 360;
    double circularity_um = 0;  ///< G
    double radial_max_um = 0, radial_min_um = 0;
    std::optional<double> feed_in_end_s, feed_in_lag_ms, data_start_s, data_end_s;
    std::optional<double> samples;     ///< samples in the data arc
    std::vector<double> angle_deg;     ///< polar plot: the axes' angle (lag included), 0° = +p towards +q
    std::vector<double> deviation_um;  ///< polar plot: radial deviation from the common least-squares circle
    /// The diagnosed model's curve (the stored result's): the commanded angle travelled since the data
    /// arc began, and the model's radial deviation about its own least-squares circle (min/max per 0.5°).
    std::vector<double> model_arc_deg, model_deviation_um;
    std::vector<double> model_angle_deg;  ///< polar plot: model_arc_deg at the axes' angle, as angle_deg
};

/// One diagnostic of a circular test, as `circle analyze` reports it.
struct CircularDiagnostic {
    std::string key;   ///< the format's JSON key, e.g. "backlash_x_um"
    std::string name;  ///< e.g. "backlash X"
    std::string unit;  ///< e.g. "µm", "ppm", "µm/m", "ms", "mm", "Hz"
    double value = 0;
    std::optional<double> uncertainty;    ///< standard uncertainty, same unit
    std::optional<double> share_percent;  ///< of the circular deviation (ranked ones)
    int rank = 0;                         ///< 1 = largest share; 0: not ranked (pitch, frequency)
    std::string action;                   ///< what to do, in the machine's terms (advice.hpp); ranked ones
};

struct CircularUnseparable {
    std::vector<std::string> keys;
    std::string reason;
    std::string combined_key;
    std::optional<double> combined_value, combined_uncertainty;
};

/// The circular test (ISO 230-4) of a session of procedure "circular": the stored result of
/// `circle analyze --store`, or the analysis made for the report.
struct CircularTest {
    std::string plane;  ///< "XY", "YZ", "ZX"
    double radius_mm = 0, feed_mm_min = 0, feed_in_mm = 0;
    Vec3 centre_mm = Vec3::Zero();
    std::optional<double> sample_rate_hz, samples_used;
    std::vector<CircularRun> runs;
    std::optional<double> bidirectional_um;  ///< G(b)
    std::optional<double> hysteresis_um;     ///< H, circular hysteresis (ISO 230-4)
    double radial_max_um = 0, radial_min_um = 0;
    std::vector<CircularDiagnostic> diagnostics;  ///< ranked first (by share), then the others
    std::vector<std::string> not_detected;
    std::vector<CircularUnseparable> unseparable;
    std::optional<double> residual_rms_um, mean_radius_um, mean_radius_uncertainty_um;
    Range bar_temp_C, air_temp_C;        ///< over the trace (air: the trace's column; bar: when it had one)
    std::string instrument;              ///< the trace's instrument header, as text
    std::optional<double> tolerance_um;  ///< allowed G: from the command line, else the stored result's
    std::string tolerance_source;        ///< "given", "stored with the result" or empty
    std::string source;                  ///< where the figures come from, e.g. "stored result 3 (…)"
    double plot_deviation_um = 0;        ///< the polar plot's half range (µm at the outer ring)
    bool pass() const;                   ///< every run's G within the tolerance (false without one)
};

struct Report {
    Header header;
    std::optional<CircularTest> circular;  ///< sessions of procedure "circular"
    std::string circular_note;             ///< why a circular session has no circular figures
    std::vector<ProcedureEvent> procedure;
    std::vector<LocationError> locations;
    std::vector<OrientationError> orientation;
    BarTrace trace;
    std::vector<CaptureWindow> captures;
    std::optional<IdentifiedModel> model;
    std::vector<DiscoveryStep> discovery;
    std::vector<std::string> discovery_notes;  ///< the noise floor and the verdicts on the residual
    std::vector<CompensationAxis> compensation;
    std::string compensation_metric;  ///< what the bars show, e.g. "max |error| over the check path"
    /// The tolerances the SSM results are judged against: the machine file's, stored with the session's
    /// plan, or given (set_ssm_tolerances); none: no verdict. Each with where it came from.
    std::optional<double> location_tolerance_um, angle_tolerance_arcsec;
    std::string location_tolerance_source, angle_tolerance_source;  ///< "machine file" or "given"
    /// A plan test's own tolerances (the stored plan's tests[].tolerances), by test (0-based: locations
    /// 2t and 2t + 1), each in place of the one above for that test; a value given replaces them all.
    std::vector<std::optional<double>> test_location_tolerance_um, test_angle_tolerance_arcsec;
    /// The tolerance a location (LocationError::location) is judged against; none: not judged.
    std::optional<double> location_tolerance_at(int location) const;
    /// The tolerance an orientation error is judged against: its test's own when both its locations are
    /// that test's, else the machine's.
    std::optional<double> angle_tolerance_for(const OrientationError& o) const;
};

/// The SSM results against the tolerances: each judged figure beyond its tolerance, in words.
struct SsmVerdict {
    bool judged = false;                ///< a tolerance and something to judge against it
    bool pass = false;                  ///< judged, and nothing beyond tolerance
    std::size_t checked = 0;            ///< figures judged
    std::vector<std::string> failures;  ///< "L3 |ΔV| 27.31 µm > 20 µm", "Δβ (test 2) 41.20″ > 30″"
};
SsmVerdict ssm_verdict(const Report& report);

/// Judges a circular test against `tolerance_um` (G, µm) given by the user instead of the stored one.
/// No effect on a report without a circular test.
void set_circular_tolerance(Report& report, double tolerance_um);

/// Judges the SSM results against the user's tolerances: a location passes when |ΔV| is within
/// `location_um`, an orientation error when |exact| is within `angle_arcsec` (to_json's "pass" on each;
/// null where no tolerance is given or the value is unknown). The uncertainties are not subtracted: they
/// are reported beside each value (docs/report.md). A value given replaces the machine file's; one not
/// given leaves it.
void set_ssm_tolerances(Report& report, std::optional<double> location_um, std::optional<double> angle_arcsec);

/// The same content as data (schema "ballbar-report/1", docs/report.md).
nlohmann::json to_json(const Report& report);

/// Renders the report as a vector PDF on A4 pages. Throws ReportError if the file cannot be written
/// (written through fileio::OutputFile: a temporary file renamed over `path`, never through a symlink).
/// Returns the number of pages.
int render_pdf(const Report& report, const std::string& path);
/// The same PDF as bytes, for the caller to write; `pages` receives the number of pages.
std::string render_pdf_bytes(const Report& report, int* pages = nullptr);

}  // namespace ballbar::report
