// SPDX-License-Identifier: MIT
// The kinematics of the `ballbarkins` LinuxCNC module (docs/linuxcnc.md), free of LinuxCNC: a
// table-tilting XYZAC machine (TTTRR) whose joints are the nominal joints plus the first-order
// correction of an identified `ballbar-model/1` — the same Compensator `ballbar compensate` uses.
//
// Units are LinuxCNC's: mm and degrees; joints and axes in the order X, Y, Z, A, C. The world
// coordinates of the tool-centre-point type are those of LinuxCNC's xyzac-trt-kins: the machine
// coordinates at A = C = 0, with the tool-length offset included (the world point is the tool tip
// plus `tool_offset_mm` along +Z, as motion hands it to the kinematics).
#pragma once

#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/analysis/compensate.hpp"
#include "ballbar/analysis/types.hpp"

namespace ballbar::linuxcnc {

/// X, Y, Z (mm), A, C (degrees).
using Axes = std::array<double, 5>;

/// LinuxCNC's switchable kinematics types: tool-centre point (the machine's TCP kinematics) and
/// identity (joint mode). Which of them is type 0 is chosen by `sparm=identityfirst`.
enum class KinsType { tcp, identity };

/// The model file cannot be used: the message names the file and the problem.
class KinsLoadError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// The settings of LinuxCNC's own xyzac-trt-kins that give the same nominal kinematics (its pins
/// x/y/z-rot-point, y-offset, z-offset; tool-offset as ballbarkins's).
struct XyzacTrtSettings {
    double x_rot_point = 0, y_rot_point = 0, z_rot_point = 0;
    double y_offset = 0, z_offset = 0;
};

/// One inverse evaluation.
struct InverseResult {
    Axes joints{};
    Axes correction{};      ///< joints − nominal joints (mm, degrees)
    bool singular = false;  ///< a rotary axis within the singular tolerance of the tool axis: not corrected
};

class CompensatingKins {
  public:
    /// A TTTRR geometry and its error parameters (and static learned terms). Throws KinsLoadError
    /// for another machine type.
    CompensatingKins(const analysis::MachineGeometry& geometry, const analysis::ErrorParams& errors,
                     std::vector<analysis::LearnedTerm> terms = {});

    /// Reads a `ballbar-model/1` file (storage's codec: strict). Throws KinsLoadError naming the file.
    static CompensatingKins from_model_file(const std::string& path);

    /// Joints for the world (TCP type) or axis (identity type) position. With `enable` false the
    /// correction is zero: the nominal kinematics. Allocates nothing, throws nothing.
    InverseResult inverse(KinsType type, const Axes& world, double tool_offset_mm, bool enable) const noexcept;
    /// The world position whose inverse gives `joints` (the correction inverted by fixed-point
    /// iteration, converged to 1e-12 mm / 1e-12° in 2–4 steps for corrections of tens of µm).
    Axes forward(KinsType type, const Axes& joints, double tool_offset_mm, bool enable) const noexcept;

    XyzacTrtSettings xyzac_equivalent() const;
    const analysis::MachineGeometry& geometry() const { return geometry_; }
    /// FNV-1a of the model file's bytes (0 when built from values): what the module's pin shows.
    std::uint32_t model_hash() const { return hash_; }

  private:
    Axes correction(const analysis::Pose& nominal_joints, const analysis::Vec3& tool_mm, bool& singular) const;
    analysis::MachineGeometry geometry_;
    analysis::Compensator compensator_;
    std::uint32_t hash_ = 0;
};

/// The compensator's options in the module: the same defaults as `ballbar compensate` (singular
/// within 0.06°, at most 0.1° of rotary correction in one step).
analysis::CompensationOptions module_compensation_options();

/// FNV-1a (32 bits) of a text.
std::uint32_t fnv1a(std::string_view bytes);

}  // namespace ballbar::linuxcnc
