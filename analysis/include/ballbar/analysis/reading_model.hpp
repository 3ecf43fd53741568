// SPDX-License-Identifier: MIT
// The bar reading the actual kinematics predict, with its gradient with respect to every error
// parameter and to the socket's position, in closed form.
//
// It is the model of kinematics.hpp's predicted_reading() (the tests hold the two to 1e-12 mm and
// this gradient to the AutoDiff derivatives of the templated kinematics), written for speed:
// identification and discovery evaluate it for every reading at every Jacobian, and forward-mode
// AutoDiff with one derivative per parameter costs about thirty times as much. The derivation is in
// docs/identification.md ("Jacobian").
#pragma once

#include <array>

#include "ballbar/analysis/error_params.hpp"
#include "ballbar/analysis/kinematics.hpp"
#include "ballbar/analysis/types.hpp"

namespace ballbar::analysis {

class ReadingModel {
  public:
    ReadingModel(const MachineGeometry& geom, const ErrorParams& e);

    struct Gradient {
        std::array<double, kParamCount> params{};  ///< ∂reading/∂parameter (parameters absent from the type: 0)
        Vec3 socket_mm = Vec3::Zero();             ///< ∂reading/∂(socket position)
    };

    /// cos and sin of a pose's rotary angles (A, B, C): they depend on the reading, not on the error
    /// parameters, so a fit evaluating the model many times computes them once per reading.
    struct RotaryTrig {
        std::array<double, 3> cos{1, 1, 1}, sin{0, 0, 0};
        explicit RotaryTrig(const Pose& pose);
    };

    /// The predicted reading (mm); with `grad`, also its gradient.
    double predict(const Pose& pose, const Vec3& socket_mm, const ReadingConditions& cond,
                   Gradient* grad = nullptr) const;
    /// The same with the pose's RotaryTrig given (the same result, bit for bit).
    double predict(const Pose& pose, const RotaryTrig& trig, const Vec3& socket_mm, const ReadingConditions& cond,
                   Gradient* grad = nullptr) const;

  private:
    // An actual rotary axis: x ↦ q + R(θ + zero)(x − q), R about `dir`. `dir` = Q·(nominal axis)
    // with Q the product of its two tilt rotations; ∂Q/∂tilt = [w]×·Q.
    struct Axis {
        Vec3 offset = Vec3::Zero();  // the location error part of q (q = base point + offset)
        Vec3 dir = Vec3::UnitX();
        Mat3 outer = Mat3::Zero();  // dir·dirᵀ
        double cos_zero = 1, sin_zero = 0;
        std::array<Param, 2> off{};   // the location errors, along unit vectors off_dir
        std::array<Vec3, 2> off_dir;  // (unit vectors)
        std::array<Param, 2> tilt{};  // the tilt errors, with their w
        std::array<Vec3, 2> w;
        Param zero{};
        Mat3 rotation(double cos_angle, double sin_angle) const;
        /// Adds g·u·∂p'/∂(this axis's parameters) to `grad`, p' = q + R(p − q), for a rotation
        /// that took p (relative to q: `rel_in`) to p' (`rel_out` = p' − q).
        void gradient(const Mat3& r, const Vec3& u, const Vec3& rel_in, const Vec3& rel_out, double g,
                      std::array<double, kParamCount>& grad) const;
    };

    MachineGeometry geom_;
    ErrorParams e_;
    Vec3 tool_mm_ = Vec3::Zero();  // the tool ball relative to the spindle pivot, tool length applied
    Axis a_, b_, c_;
};

}  // namespace ballbar::analysis
