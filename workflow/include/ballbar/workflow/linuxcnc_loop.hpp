// SPDX-License-Identifier: MIT
// The whole loop on a real controller (`ballbar demo --controller linuxcnc`, docs/linuxcnc.md "The loop"):
// LinuxCNC's headless simulator runs the part programs the guided SSM procedure writes, with the
// `ballbarkins` kinematics module in its servo loop; the joints it commands every servo cycle reach the
// emulated five-axis machine (with its geometric errors) through LinuxCNC's own sampler
// (`halsampler` → a FIFO → device::TrajectoryFeed), and the emulated ball-bar on that machine streams
// through a pseudo-terminal and the real serial path to the procedure, as a real bar would. LinuxCNC
// decides how the machine moves: its interpreter, planner, feeds, dwells and program stops.
//
//   1. the SSM with `ballbarkins` disabled (the nominal kinematics) → a stored session;
//   2. identification of the machine's error model from that session;
//   3. the model loaded into `ballbarkins` (LinuxCNC restarted with it), compensation on;
//   4. the same SSM again → a second stored session;
//   (after each SSM, with LinuxCNC still running: the ISO 230-4 circular test in the machine's XY plane
//   about the same socket with the table tilted, A = 30°: G and the radial deviation before and after);
//   5. each location's total position error per axis, before and after, and the gain;
//   6. optionally (`discover`): the discovery workflow on the first session names what the model misses;
//      the extended model goes into `ballbarkins` and a third SSM shows the gap shrink.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/acquisition/interfaces.hpp"
#include "ballbar/acquisition/plan.hpp"
#include "ballbar/analysis/circular.hpp"
#include "ballbar/analysis/error_params.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::workflow {

struct LinuxcncLoopOptions {
    std::uint64_t seed = 1;  ///< the bar's noise
    /// Where LinuxCNC's configuration, the programs, the model and the logs go: a directory that does
    /// not exist yet (created, kept), or empty for a new one under $TMPDIR (kept: its path is in the result).
    std::string work_dir;
    /// The built `ballbarkins.so` (a build tree's): linked as /usr/lib/linuxcnc/modules/ballbarkins.so
    /// when nothing but such a link is there (root only). Empty: the installed module.
    std::string module_path;
    std::optional<acquisition::PlanSpec> plan;  ///< default: loop_plan()
    /// The emulated machine's true errors (default: loop_errors()).
    std::optional<analysis::ErrorParams> errors;
    /// After the second measurement, run the discovery workflow on the first session; when it names
    /// effects, load the extended model into ballbarkins and measure a third time.
    bool discover = false;
    /// After each SSM, the circular test loop_circle() through LinuxCNC (about a minute each).
    bool circle = true;
};

struct LinuxcncLoopEvents {
    std::function<void(std::string_view)> message;  ///< each step as it begins, and LinuxCNC's state
    std::function<void(const acquisition::Progress&)> progress;
};

/// One location of the plan, measured before and after compensation: the total position error (SSM's e,
/// the tool ball relative to the table ball against nominal), mm. From one socket the zero offsets of A
/// and C (A_zero, C_zero) cannot be told from the socket's set-up error (identify says they are
/// unobservable): their effect is a socket offset no compensation removes, and which turns with the
/// table. The machine's error is e less the set-up offset that best explains it: the offset s (table
/// frame) minimising Σ|e + Rx(A)·Rz(C)·s|² over the measurement's locations — one rule for every
/// measurement, no model in it.
struct LoopLocation {
    int test = 0, step = 1;
    analysis::Vec3 before_mm = analysis::Vec3::Zero(), after_mm = analysis::Vec3::Zero();  ///< e as measured
    /// e with the extended model of the discovery in ballbarkins (the third measurement), when there was one.
    std::optional<analysis::Vec3> third_mm;
    /// What the emulated machine's true errors give there with the nominal kinematics: `before_mm`
    /// should be it, when LinuxCNC put the machine at the planned poses.
    analysis::Vec3 true_before_mm = analysis::Vec3::Zero();
    /// The machine's error: e less its measurement's set-up offset as it stands at this pose.
    analysis::Vec3 machine_before_mm = analysis::Vec3::Zero(), machine_after_mm = analysis::Vec3::Zero();
    std::optional<analysis::Vec3> machine_third_mm;
};

/// One circular test of the loop (a stored session of its own).
struct LoopCircle {
    std::string phase;  ///< "before", "after", "extended" (the third measurement)
    std::int64_t session = 0;
    double g_um = 0;             ///< G(b): bidirectional circular deviation about the least-squares centre
    double radial_range_um = 0;  ///< F's max − min: the deviation from the programmed circle (centre offset in it)
    double mean_radius_um = 0;   ///< mean measured − programmed radius
};

struct LinuxcncLoopResult {
    std::string work_dir;
    std::int64_t before_session = 0, after_session = 0;
    std::string model_path;               ///< the identified model, as loaded into ballbarkins
    std::uint32_t model_hash = 0;         ///< FNV-1a of its bytes (ballbarkins.model-hash)
    std::vector<std::string> identified;  ///< "Y0A = -12.3 µm" per estimated parameter
    std::vector<LoopLocation> locations;
    /// The machine's error (the set-up offset taken out), RMS over the locations, per axis X Y Z.
    std::array<double, 3> rms_before_um{}, rms_after_um{};
    double gain(int axis) const;  ///< before / after (0 when after is 0)
    /// e as measured (the set-up offset in it), RMS over the locations, per axis.
    std::array<double, 3> rms_raw_before_um{}, rms_raw_after_um{};
    /// The set-up offset each measurement's e holds (table frame; see LoopLocation): before, after, third.
    analysis::Vec3 setup_before_mm = analysis::Vec3::Zero(), setup_after_mm = analysis::Vec3::Zero(),
                   setup_third_mm = analysis::Vec3::Zero();
    analysis::Vec3 identified_setup_mm = analysis::Vec3::Zero();  ///< the identified model's socket offset
    std::uint64_t servo_cycles = 0;   ///< joint samples LinuxCNC sent the emulated machine, every run
    std::vector<LoopCircle> circles;  ///< the circular test after each SSM (LinuxcncLoopOptions::circle)

    // The discovery (LinuxcncLoopOptions::discover).
    bool discovery_ran = false;
    std::vector<std::string> discovered;  ///< "squareness_XY (C0Y) = 41.2 µrad" per effect the workflow added
    std::string discovery_verdict;        ///< what remains after it, against the instrument's noise
    std::int64_t third_session = 0;       ///< 0: no third measurement (discovery named nothing)
    std::string extended_model_path;
    std::array<double, 3> rms_third_um{};  ///< the machine's error with the extended model, RMS per axis
    double third_gain(int axis) const;     ///< before / third (0 without a third measurement)
};

/// Empty when LinuxCNC can run the loop here, else why not (not installed, module missing, not root).
std::string linuxcnc_loop_unavailable(const std::string& module_path);

/// The loop's machine: a TTTRR (XYZAC table-tilting) machine in LinuxCNC's dialect, the geometry of the
/// simulator configuration, and a plan of four tests at one socket on the table.
acquisition::MachineFile loop_machine();
acquisition::PlanSpec loop_plan();
/// The loop's circular test: ISO 230-4 in the machine's XY plane, radius the plan's bar length, centred on
/// the plan's first socket as it stands with the table at A = `a_deg` (C = 0); both directions.
analysis::circular::TestSpec loop_circle(const acquisition::MachineFile& machine, const acquisition::PlanSpec& plan,
                                         double a_deg = 30.0);
/// Why `--hidden ID` cannot hide that effect in the loop's machine (empty: it can): an unknown id, one
/// already in the loop's model, one of the bar's (no controller compensates the instrument) or of time
/// and temperature (the loop's sessions last minutes: it would not show).
std::string hidden_effect_refusal(std::string_view id);
/// The size `--hidden` gives an effect of the machine's geometry outside the loop's model: visible, of a
/// real machine's order (40 µrad of squareness or tilt, 40 µm/m of scale, 15 µm of a length).
double hidden_effect_size(analysis::Param p);

/// Seed-like errors of the rotary axes' locations (the link errors the second seed identifies). Set 0 is
/// the demo machine's; set k > 0 draws each of the same parameters at random (deterministic in k) with
/// the same size: uniform in ±1.5 times the demo's magnitude of that kind.
analysis::ErrorParams loop_errors(int set = 0);

/// Runs the loop into `store`. Error (device) when LinuxCNC cannot run or reports an error, Error
/// (failed) when a session does not complete or a stored point is away from its pose.
LinuxcncLoopResult run_linuxcnc_loop(storage::Store& store, const LinuxcncLoopOptions& options,
                                     const LinuxcncLoopEvents& events = {});

}  // namespace ballbar::workflow
