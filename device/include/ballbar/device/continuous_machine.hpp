// SPDX-License-Identifier: MIT
// Continuous motion of a machine's three linear axes for the circular test (docs/emulator.md,
// "Continuous motion"): the machine runs a part program of straight moves and arcs (G0, G1, G2, G3 in
// G17/G18/G19, G4), each axis follows its command through a first-order servo lag, and every effect of
// the trace format's table (docs/formats/trace.md) moves the lagged axes exactly as defined there:
// lost motion, reversal spikes, scale, squareness, cyclic error, straightness, plus a radial vibration.
// The bar measures from the tool ball to the socket, which the operator put at the program's circle
// centre (plus a set-up offset).
//
// Time is the caller's simulated clock (seconds since power-on); `bar_length_mm` must be asked at
// non-decreasing times (it integrates the lag). Thread-safe: a host samples it while another thread
// starts a program.
#pragma once

#include <array>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ballbar/analysis/circular.hpp"
#include "ballbar/analysis/nc_program.hpp"

namespace ballbar::device {

using Xyz = std::array<double, 3>;

/// One axis's own errors (trace.md's definitions, applied to the lagged axis).
struct AxisErrors {
    double servo_lag_ms = 0;       ///< first-order lag τ of the axis behind its command
    double backlash_um = 0;        ///< lost motion b: e = −sign(v)·b/2
    double reversal_spike_um = 0;  ///< h: e = (old direction)·h·exp(−Δt / 15 ms) after a reversal
    double scale_ppm = 0;          ///< s: e = s·position
    double cyclic_um = 0;          ///< c: e = c·sin(2π·position/λ + φ)
    double cyclic_pitch_mm = 0;    ///< λ (0: no cyclic error)
    double cyclic_phase_deg = 0;   ///< φ
};

/// Every error of the continuous machine. Indices: axes 0, 1, 2 = X, Y, Z.
struct ContinuousErrors {
    std::array<AxisErrors, 3> axis;
    /// Squareness of each plane in that plane's convention (trace.md): XY e_x = α·y, YZ e_y = α·z,
    /// ZX e_z = α·x; α in µm/m, indexed XY, YZ, ZX.
    std::array<double, 3> squareness_um_per_m{0, 0, 0};
    /// [i][j]: axis i's motion bows in axis j, e_j = k·(i − socket_i)², k in µm/m² (about the socket,
    /// the circle centre: trace.md's straightness reported k·R²).
    std::array<Xyz, 3> straightness_um_per_m2{};
    double vibration_um = 0;  ///< radial a·sin(2π·f·t + φ)
    double vibration_hz = 0;
    double vibration_phase_deg = 0;
};

struct ContinuousSetup {
    ContinuousErrors errors;
    Xyz start_mm{0, 0, 0};          ///< where the axes stand at power-on
    Xyz socket_mm{0, 0, 0};         ///< the socket before a program names its circle centre
    Xyz socket_offset_mm{0, 0, 0};  ///< set-up error of the socket (against the programmed centre)
    double rapid_mm_min = 10000;    ///< G0 speed
};

/// One piece of the commanded path.
struct PathSegment {
    enum class Kind { Line, Arc, Dwell };
    Kind kind = Kind::Line;
    Xyz from{}, to{};
    Xyz centre{};                         ///< arc: centre (the third axis's value is unused)
    int p = 0, q = 1;                     ///< arc: the plane's axes (G17 X,Y; G18 Z,X; G19 Y,Z)
    double start_rad = 0, sweep_rad = 0;  ///< arc: angle of `from` about the centre, signed sweep (G3 > 0)
    double r0 = 0, r1 = 0;                ///< arc: radius at the start and the end
    double duration_s = 0;
    bool has_centre = false;  ///< an arc (its centre is where the socket goes)
};

/// The motion of a part program of the subset `circle plan` writes: G90/G21, G0, G1, G2, G3 (centre words
/// I J K, incremental from the start point), G4 (P: ms in Fanuc, s in LinuxCNC), G17/G18/G19, F,
/// comments, "%" and O-number lines, M codes (ignored). Throws analysis::NcError with the line.
std::vector<PathSegment> parse_motion_program(std::string_view text, analysis::NcDialect dialect, const Xyz& start_mm,
                                              double rapid_mm_min, double feed_override = 1.0);

/// One diagnostic of a circular test's result against the emulator's truth, judged by the accuracy rule
/// of docs/circular.md: an injected effect within 20 % or the equivalent of 0.25 µm of radial amplitude
/// (whichever is larger; pitch and frequency within 5 %), an absent one reported below twice that.
struct TruthComparison {
    analysis::circular::Diag diag = analysis::circular::Diag::BacklashP;
    std::string key;
    double truth = 0;
    std::optional<double> measured;  ///< empty: not reported (unseparable, or pitch of an undetected error)
    double std_uncertainty = 0;
    double allowed = 0;  ///< the allowed error (injected) or the largest allowed report (absent)
    bool injected = false;
    bool pass = true;
    std::string note;
};
std::vector<TruthComparison> compare_with_truth(const analysis::circular::CircularResult& result,
                                                const std::vector<std::pair<analysis::circular::Diag, double>>& truth);

class ContinuousMachine {
  public:
    explicit ContinuousMachine(ContinuousSetup setup);

    const ContinuousSetup& setup() const { return setup_; }

    /// Stops wherever the command is at `t_s` (or later: the clock's latest time) and runs the program
    /// from there; the socket is at the first arc's centre plus its set-up offset. Throws NcError.
    void run_program(std::string_view text, analysis::NcDialect dialect, double t_s);
    void set_feed_override(double factor);
    /// The commanded position at `t_s`.
    Xyz commanded_mm(double t_s) const;
    /// End of the programmed motion (≤ now when idle).
    double program_end_s() const;
    bool idle_at(double t_s) const { return program_end_s() <= t_s; }
    Xyz socket_mm() const;

    /// The bar length (tool ball to socket, mm) at `t_s` ≥ the last time asked.
    double bar_length_mm(double t_s);
    /// The actual (lagged, erroneous) tool ball position at `t_s` ≥ the last time asked.
    Xyz actual_mm(double t_s);

    /// What a circular test in `plane` at `radius_mm` should report for each diagnostic of the format
    /// (trace.md's keys), from these errors. Pitch and frequency only where an amplitude is set.
    std::vector<std::pair<analysis::circular::Diag, double>> truth(analysis::circular::Plane plane,
                                                                   double radius_mm) const;

  private:
    void advance_locked(double t_s);
    Xyz command_locked(double t_s) const;
    Xyz actual_locked() const;

    ContinuousSetup setup_;
    mutable std::mutex mutex_;
    double feed_override_ = 1.0;
    std::vector<PathSegment> path_;
    std::vector<double> t0_;  ///< start time of each path segment
    Xyz rest_mm_;             ///< where the command stands before the path (and after it: path end)
    Xyz socket_;              ///< nominal socket position
    // Integrator state at time now_.
    double now_ = 0;
    Xyz axis_{};      ///< lagged axis positions
    Xyz velocity_{};  ///< lagged axis velocities, mm/s
    std::array<int, 3> direction_{0, 0, 0};
    std::array<double, 3> reversal_t_{-1e30, -1e30, -1e30};
    std::array<int, 3> reversal_old_{0, 0, 0};
};

}  // namespace ballbar::device
