// SPDX-License-Identifier: MIT
// The volumetric summary of circular tests in the three planes (docs/circular.md, "Volumetric").
#include <Eigen/Dense>
#include <cmath>

#include "ballbar/analysis/circular.hpp"

namespace ballbar::analysis::circular {
namespace {

constexpr const char* kAxis[3] = {"x", "y", "z"};

const DiagnosticResult* usable(const CircularResult& r, Diag diag) {
    const DiagnosticResult* d = r.find(diag);
    return d && d->detected && d->std_uncertainty >= 0.0 ? d : nullptr;
}

}  // namespace

VolumetricResult combine_volumetric(const std::vector<CircularResult>& planes) {
    VolumetricResult out;
    bool seen[3] = {false, false, false};
    for (const auto& r : planes) {
        const int k = static_cast<int>(r.test.plane);
        if (seen[k]) throw CircularError(std::string("plane ") + plane_name(r.test.plane) + " given twice");
        seen[k] = true;
    }
    // Squareness of each plane as measured.
    for (Plane plane : {Plane::XY, Plane::YZ, Plane::ZX}) {
        VolumetricFigure f;
        const auto axes = plane_axes(plane);
        f.key = std::string("squareness_") + axes[0] + axes[1] + "_um_per_m";
        for (const auto& r : planes)
            if (r.test.plane == plane)
                if (const auto* d = usable(r, Diag::Squareness))
                    f.value = d->value, f.std_uncertainty = d->std_uncertainty, f.known = true;
        out.figures.push_back(f);
    }
    // Backlash of each axis: weighted mean over the planes that contain it.
    for (int axis = 0; axis < 3; ++axis) {
        double sw = 0.0, swx = 0.0;
        for (const auto& r : planes) {
            const auto idx = plane_axis_index(r.test.plane);
            for (int j = 0; j < 2; ++j) {
                if (idx[static_cast<std::size_t>(j)] != axis) continue;
                const auto* d = usable(r, j == 0 ? Diag::BacklashP : Diag::BacklashQ);
                if (!d) continue;
                const double w = 1.0 / std::max(d->std_uncertainty * d->std_uncertainty, 1e-12);
                sw += w, swx += w * d->value;
            }
        }
        VolumetricFigure f;
        f.key = std::string("backlash_") + kAxis[axis] + "_um";
        if (sw > 0.0) f.value = swx / sw, f.std_uncertainty = std::sqrt(1.0 / sw), f.known = true;
        out.figures.push_back(f);
    }
    // Scale of each axis: mismatches s_p − s_q and mean radius (s_p + s_q)/2, weighted least squares.
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    auto add = [&](const Eigen::Vector3d& row, double value, double sigma) {
        const double w = 1.0 / std::max(sigma * sigma, 1e-12);
        ata += w * row * row.transpose();
        atb += w * row * value;
    };
    for (const auto& r : planes) {
        const auto idx = plane_axis_index(r.test.plane);
        Eigen::Vector3d row = Eigen::Vector3d::Zero();
        if (const auto* d = usable(r, Diag::ScaleMismatch)) {
            row[idx[0]] = 1.0, row[idx[1]] = -1.0;
            add(row, d->value, d->std_uncertainty);
        }
        row.setZero();
        row[idx[0]] = 0.5, row[idx[1]] = 0.5;
        add(row, r.mean_radius_um * 1e3 / r.test.radius_mm, r.mean_radius_std_um * 1e3 / r.test.radius_mm);
    }
    const Eigen::FullPivLU<Eigen::Matrix3d> lu(ata);
    const bool solvable = lu.rank() == 3;
    Eigen::Vector3d s = Eigen::Vector3d::Zero();
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    if (solvable) s = lu.solve(atb), cov = lu.inverse();
    for (int axis = 0; axis < 3; ++axis) {
        VolumetricFigure f;
        f.key = std::string("scale_") + kAxis[axis] + "_ppm";
        if (solvable) f.value = s[axis], f.std_uncertainty = std::sqrt(std::max(cov(axis, axis), 0.0)), f.known = true;
        out.figures.push_back(f);
    }
    return out;
}

}  // namespace ballbar::analysis::circular
