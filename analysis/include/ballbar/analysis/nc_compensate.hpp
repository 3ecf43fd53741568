// SPDX-License-Identifier: MIT
// A part program through an identified error model (docs/compensation.md): NcInterpreter gives each
// block's motion as segments with absolute end points; each end point is mapped to the model's
// commanded pose (work offset, tool length, and in tool-centre-point mode the controller's nominal
// inverse kinematics), compensated (compensate.hpp), mapped back to the program's frame and written.
// Streams: the text is read and written a block at a time.
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/analysis/compensate.hpp"
#include "ballbar/analysis/nc_interpreter.hpp"

namespace ballbar::analysis {

struct NcCompensateOptions {
    bool exact = false;
    CompensationOptions solver;
    double max_linear_mm = 1.0;               ///< a larger correction is refused (unless `force`)
    double max_rotary_rad = deg_to_rad(0.1);  ///< likewise; also the most a compensated angle may move
    bool force = false;
    bool allow_truncated = false;  ///< a program without M2/M30/% is compensated as it is (no end added)
    int decimals = 4;              ///< digits after the point of the axis words (mm and degrees)
    std::string title;
    /// Empirical terms learned by discovery (rotary angular error tables, positioning polynomials),
    /// applied by the actual machine model with the error parameters (docs/discovery.md).
    std::vector<LearnedTerm> empirical;
};

struct NcCompensateSummary {
    std::size_t blocks = 0;  ///< blocks read
    std::size_t moves = 0;   ///< blocks with motion
    std::size_t points = 0;  ///< end points compensated (an arc gives several)
    std::size_t arcs = 0, arc_chords = 0;
    std::size_t joint_moves = 0, tcp_moves = 0;          ///< motion blocks in each frame
    std::vector<std::pair<int, NcFrame>> mode_switches;  ///< line and the frame from there (first 50)
    std::size_t retracts = 0;                            ///< "G91 G28 Z0" lines copied uncompensated
    double max_linear_mm = 0, max_rotary_rad = 0;
    int max_linear_line = 0, max_rotary_line = 0;
    std::size_t singular = 0;
    std::vector<int> singular_lines;  ///< first 20
    std::size_t not_converged = 0;    ///< --exact: points whose Newton iteration missed its tolerances
    std::vector<int> not_converged_lines;
    std::size_t over_bound = 0;  ///< with `force`: corrections beyond the bounds, written anyway
    bool truncated = false;      ///< no program end (allowed by `allow_truncated`)
    PoseRange commanded;         ///< the machine poses compensated (work offsets applied), with their lines
};

/// Receives the output text in chunks (about 1 MiB).
using NcSink = std::function<void(std::string_view)>;

/// Compensates `text`. Throws NcError (line and reason) for what it refuses: the interpreter's
/// refusals, a non-finite or out-of-bound correction (unless `force`), a program without an end
/// (unless `allow_truncated`), an empty program; tool-centre-point mode and G43 on a head machine.
NcCompensateSummary compensate_nc_program(std::string_view text, const MachineGeometry& geometry,
                                          const ErrorParams& errors, const NcInterpreterOptions& interpretation,
                                          const NcCompensateOptions& options, const NcSink& sink);

/// The controller's nominal tool-centre-point kinematics of a TTTRR machine (the table frame of
/// docs/kinematics.md with world coordinates = machine coordinates at A = C = 0): the machine
/// position of the tool point for a workpiece point w and the angles, and back.
Vec3 tcp_inverse(const MachineGeometry& g, const Vec3& w, double a_rad, double c_rad);
Vec3 tcp_forward(const MachineGeometry& g, const Vec3& machine, double a_rad, double c_rad);

}  // namespace ballbar::analysis
