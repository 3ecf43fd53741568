// SPDX-License-Identifier: MIT
// Compensation of a commanded pose through the inverse Jacobian, for the three seed machine types
// with an identified error model (docs/compensation.md).
//
// The tool pose that matters is the tool relative to the workpiece: the tool-ball centre and the tool
// axis expressed in the table frame (the frame of the readings' socket coordinates). For a commanded
// pose u the intended tool pose is the nominal one, v_nom(u); the machine delivers v_act(u). The
// correction du makes v_act(u + du) = v_nom(u):
//  - first order (Lei & Hsu's method): du = J⁺ (v_nom(u) − v_act(u)) with J the nominal Jacobian at u,
//    the rotary part by least squares over the three direction components (singular only where a
//    rotary axis is parallel to the tool axis, the true singularity);
//  - exact: Newton iteration on the same equations until the position matches to `tolerance_mm`.
// Near a singularity (|sin| of the angle between a rotary axis and the tool axis below
// `singular_tolerance`) that axis is not corrected (seed-math.md: no C correction at A = 0) and the
// position is still matched exactly by the linear axes.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "ballbar/analysis/empirical.hpp"
#include "ballbar/analysis/error_params.hpp"
#include "ballbar/analysis/types.hpp"

namespace ballbar::analysis {

/// Tool-ball centre (mm) and unit tool axis (pointing from the ball into the spindle) in the table frame.
struct ToolPose {
    Vec3 position_mm = Vec3::Zero();
    Vec3 direction = Vec3::UnitZ();
};

/// The actual kinematics of one machine with fixed error parameters, precomputed for fast evaluation
/// (the same model as kinematics.hpp's actual_tool_ball/actual_table_ball, time 0: no spindle growth).
class MachineModel {
  public:
    MachineModel(const MachineGeometry& geom, const ErrorParams& e);
    /// With learned empirical terms (empirical.hpp): a rotary axis turns by commanded + zero offset +
    /// ε(commanded), ε its angular error table (rotary pitch-error compensation); a linear axis moves
    /// to commanded + δ(commanded). Terms that depend on time, temperature or the approach direction
    /// are not part of a static model and are ignored.
    MachineModel(const MachineGeometry& geom, const ErrorParams& e, std::span<const LearnedTerm> terms);

    ToolPose tool_pose(const Pose& pose) const;
    const MachineGeometry& geometry() const { return geom_; }

    /// cos and sin of the commanded rotary angles, computed once per pose and shared.
    struct Trig {
        double c1 = 1, s1 = 0, c2 = 1, s2 = 0;
    };
    static Trig trig(MachineType type, const Pose& pose);
    ToolPose tool_pose(const Pose& pose, const Trig& t) const;
    /// With the tool ball moved by `tool_shift_mm` from the geometry's (another tool in the spindle:
    /// a controller's tool-length offset).
    ToolPose tool_pose(const Pose& pose, const Trig& t, const Vec3& tool_shift_mm) const;

  private:
    ToolPose static_pose(const Pose& pose, const Trig& t,
                         const Vec3& tool_shift_mm) const;  // without the learned terms
    struct Axis {  // rotation about a fixed line: x ↦ point + R(θ + zero)(x − point)
        Vec3 point = Vec3::Zero();
        Vec3 dir = Vec3::UnitZ();
        Mat3 cross = Mat3::Zero();  // [dir]×
        Mat3 outer = Mat3::Zero();  // dir·dirᵀ
        double cos_zero = 1, sin_zero = 0;
        Mat3 rotation(double cos_angle, double sin_angle) const;  // of the commanded angle
    };
    MachineGeometry geom_;
    ErrorParams e_;
    Axis first_, second_;             // the type's rotary axes, in the order of rotary_axes(type)
    std::vector<LearnedTerm> terms_;  // the static empirical terms (angular, positioning)
    Vec3 tool_mm_ = Vec3::Zero();
    Vec3 chain_ = Vec3::Zero();  // TTTRR: qc − qa
    Vec3 base_ = Vec3::Zero();   // TTTRR: a_pivot + c_offset − qc; RTTTR: a_pivot − qa
};

/// The singularity tolerance `ballbar compensate` and `ballbar solve compensate` use by default: within
/// 0.06° of a rotary axis parallel to the tool, that axis is not corrected.
constexpr double kDefaultSingularDeg = 0.06;
double default_singular_tolerance();  ///< sin(kDefaultSingularDeg)

struct CompensationOptions {
    /// At or below this |sin(angle between a rotary axis and the tool axis)| the axis is not corrected
    /// (0 suppresses only the exactly parallel axis: never a division by zero).
    double singular_tolerance = 1e-3;
    /// A rotary increment larger than this (rad) in one step means the pose is too near a singularity
    /// for the least-squares split: the axis nearer parallel to the tool is then left uncorrected too.
    double max_rotary_step_rad = 1e300;
    int max_iterations = 20;       ///< exact solution
    double tolerance_mm = 1e-12;   ///< exact solution: position match
    double tolerance_rad = 1e-14;  ///< exact solution: direction match (non-singular poses)
};

struct Correction {
    Pose commanded;                  ///< u + du
    std::array<double, 5> du{};      ///< X, Y, Z (mm), first and second rotary axis (rad)
    bool singular = false;           ///< a rotary axis was left uncorrected
    int suppressed_axis = -1;        ///< 3 (first rotary) or 4 (second rotary) when singular
    bool converged = true;           ///< exact solution reached its tolerances
    int iterations = 0;              ///< exact solution
    double position_error_mm = 0;    ///< |position_act(u + du) − position_nom(u)| after correction
    double direction_error_rad = 0;  ///< angle between the corrected and intended tool axes
};

class Compensator {
  public:
    Compensator(const MachineGeometry& geom, const ErrorParams& e, CompensationOptions options = {});
    /// The actual machine with learned empirical terms too (MachineModel).
    Compensator(const MachineGeometry& geom, const ErrorParams& e, std::span<const LearnedTerm> terms,
                CompensationOptions options = {});

    /// First-order correction (one model evaluation, nominal Jacobian). Errors are not evaluated
    /// after the correction (position_error_mm, direction_error_rad = 0) to keep it cheap.
    Correction first_order(const Pose& u) const;
    /// The same for a tool point at `tool_ball_mm` from the commanded XYZ instead of the geometry's
    /// (a controller compensating whatever tool is in the spindle: the LinuxCNC module). Allocates
    /// nothing and throws nothing.
    Correction first_order(const Pose& u, const Vec3& tool_ball_mm) const;
    /// Exact correction by Newton iteration.
    Correction exact(const Pose& u) const;

    ToolPose nominal(const Pose& u) const { return nominal_.tool_pose(u); }
    ToolPose actual(const Pose& u) const { return actual_.tool_pose(u); }
    const CompensationOptions& options() const { return options_; }

  private:
    // The nominal machine at u, in the table frame: the intended tool pose and the Jacobian columns
    // of the two rotary axes (position cw, direction cq); `to_machine` maps a table-frame vector to
    // the machine frame (the table rotation rt).
    struct Frame {
        MachineType type = MachineType::TTTRR;
        MachineModel::Trig tr;
        Vec3 position, direction;
        Vec3 cw[2], cq[2];
        Vec3 to_machine(const Vec3& v) const;
    };
    Frame frame(const Pose& u, const MachineModel::Trig& t, const Vec3& tool_shift_mm) const;
    Correction first_order_shifted(const Pose& u, const Vec3& tool_shift_mm) const;
    // One linearised step: du from the pose error (intended − actual); `suppressed` chosen once, then kept.
    std::array<double, 5> step(const Frame& f, const Vec3& dw, const Vec3& dq, int& suppressed) const;

    MachineModel nominal_, actual_;
    CompensationOptions options_;
};

/// The pose u with du added (rotary increments to the type's two rotary axes).
Pose add_correction(MachineType type, const Pose& u, const std::array<double, 5>& du);

}  // namespace ballbar::analysis
