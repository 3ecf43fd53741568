// SPDX-License-Identifier: MIT
// The ISO 230-4 circular test's planning and analysis as use cases (`ballbar circle plan|analyze`, and
// any front end): the part program checked against the machine's travel and the instrument's reading
// rate, a planned session, the analysis of trace files and stored sessions with its result stored once,
// the volumetric summary, and the measured backlash and scale in a controller's own terms
// (docs/circular.md).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ballbar/acquisition/machine_file.hpp"
#include "ballbar/analysis/circular.hpp"
#include "ballbar/analysis/nc_program.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/storage/trace_file.hpp"
#include "ballbar/workflow/identify.hpp"  // StoreOpener

namespace ballbar::workflow {

/// The instrument's reading rate against the test's feed: the samples must lie close enough along the
/// path for the diagnosis (analysis::circular::sampling_limit). Returns the note for the operator (how
/// far apart they lie, the highest usable feed); Error (bad input) naming the highest usable feed when
/// the feed is too fast.
std::string check_feed_for_rate(const analysis::circular::TestSpec& test, double rate_hz);

/// The part program of the test (docs/formats/trace.md, "The motion"), arcs split into ≤ 90° blocks.
/// With a machine, Error (bad input) when the path leaves an axis's travel.
std::string circular_part_program(const analysis::circular::TestSpec& test, analysis::NcDialect dialect, double dwell_s,
                                  const acquisition::MachineFile* machine = nullptr);

/// A planned circular session: the test header it implies, waiting for its samples. Returns its id.
std::int64_t store_planned_circular(storage::Store& store, const analysis::circular::TestSpec& test);

/// One input of an analysis: a trace file, or a stored session's trace.
/// A circular test as a front end gives it (the CLI's options, a page's form): plane, radius, centre,
/// feed, feed-in, arc and runs (docs/circular.md, "Planning").
struct CircularTestInput {
    std::string plane = "XY";
    double radius_mm = 100.0;
    std::vector<double> centre_mm{0.0, 0.0, 0.0};
    double feed_mm_min = 1000.0;
    double feed_in_mm = 1.5;
    double arc_deg = 360.0;
    std::optional<double> overshoot_deg;  ///< default: 45 for a full circle, 20 for a partial arc
    std::optional<double> start_deg;      ///< default: 0 (full) or −overshoot (partial)
    std::string directions = "both";      ///< both (ccw, then cw from where it ended), ccw or cw
};

/// The test header the input describes, shared by the part program, the session and the analysis;
/// Error (bad input) naming the option (as the CLI spells it) when it is not a test.
analysis::circular::TestSpec circular_test_spec(const CircularTestInput& input);

struct CircularInput {
    std::string name;  ///< as given
    storage::TraceFile trace;
    std::optional<std::int64_t> session;  ///< the session it is (or was imported as)
};

struct AnalyzedCircular {
    CircularInput input;
    analysis::circular::CircularResult result;
    std::string payload_json;  ///< the result as stored (storage/circular_result.hpp)
    /// Stored with the session by this analysis; false when the session already held this very result
    /// (analysing it again stores no duplicate) or there is no session.
    bool stored = false;
};

struct CircularAnalysis {
    std::vector<AnalyzedCircular> tests;
    std::optional<analysis::circular::VolumetricResult> volumetric;  ///< with two tests or more
    std::vector<std::string> warnings;                               ///< the files' own, "name: warning"
};

struct CircularAnalyzeOptions {
    bool import_files = false;           ///< import each trace file as a session and store its result with it
    std::optional<double> tolerance_um;  ///< G allowed: the verdict stored with the result
};

/// Analyses each input: a path is a trace file; anything else a session key of the database
/// `sessions` opens (read only). `for_writing` opens the database results are stored in (a session's,
/// and an imported file's). Error (bad input) for a path that is neither, a file that is not a trace, a
/// session that is not a circular test, a trace that cannot be analysed, tests that cannot be combined.
CircularAnalysis analyze_circular_inputs(std::span<const std::string> inputs, const StoreOpener& sessions,
                                         const StoreOpener& for_writing, const CircularAnalyzeOptions& options);

/// One axis's settings for a controller, from the measured backlash and scale.
struct AxisSetting {
    char axis = 'X';                            ///< X, Y or Z
    std::optional<double> backlash_mm;          ///< what to set (never negative)
    std::string note;                           ///< e.g. a negative lost motion, not compensable
    std::string setting;                        ///< the controller's line or command for the backlash
    std::string config;                         ///< a configuration file's line for it, where the controller has one
    std::optional<double> scale_ppm;            ///< the axis's scale error
    std::optional<double> steps_per_mm_factor;  ///< multiply the current steps/mm (or SCALE) by this
    std::string scale_setting;
};

struct ControllerSettings {
    std::string controller;
    std::vector<AxisSetting> axes;  ///< the test plane's two axes
    std::string config;             ///< a line the configuration needs besides (Smoothieware)
};

/// The controllers `controller_settings` knows: linuxcnc, marlin, smoothieware, grblhal.
bool known_controller(const std::string& controller);

/// The backlash and scale of the test plane's axes in `controller`'s terms. Error (bad input) for a
/// controller it does not know.
ControllerSettings controller_settings(const analysis::circular::CircularResult& result, const std::string& controller);

}  // namespace ballbar::workflow
