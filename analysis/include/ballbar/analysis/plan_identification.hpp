// SPDX-License-Identifier: MIT
// Planning an identification: which SSM locations (rotary angle pairs × socket positions, each with a
// cube-corner of bar directions around the table ball) make the chosen parameters observable, and
// how many are needed.
//
// Greedy design (docs/identification.md): the candidates' reading Jacobians at the nominal machine
// are computed once; locations are added one at a time, each time the candidate that most raises
// Σ log(independence) over the unknowns (parameters + the socket offsets in use), until every
// parameter's independence reaches `target_independence` (or the budget is spent). Parameters that
// stay unobservable even with every candidate measured are reported as such (e.g. C_zero next to free
// socket offsets: a rotation of the socket about C is a socket offset).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "ballbar/analysis/error_params.hpp"
#include "ballbar/analysis/reading.hpp"
#include "ballbar/analysis/types.hpp"

namespace ballbar::analysis {

struct PlanOptions {
    std::vector<Param> params;  ///< parameters to make observable
    double bar_length_mm = 100.0;
    /// Candidate socket positions in the table frame; empty: the geometry's defaults (see .cpp).
    std::vector<Vec3> sockets_mm;
    /// Candidate angles of the first and second rotary axis; empty: A in [−90°, 90°] step 15°,
    /// second axis in [0°, 330°] step 30° (B of RRTTT/RTTTR in [−90°, 90°] step 15°).
    std::vector<double> first_angles_rad, second_angles_rad;
    /// Half-angle of the cone of bar directions about +Z (machine) at each location; 54.7356°:
    /// mutually orthogonal directions (cube corner), the best-conditioned SSM layout.
    double cone_half_angle_rad = 0.9553166181245093;
    int points_per_location = 3;
    bool fit_socket_offsets = true;
    double target_independence = 0.2;
    /// Keep adding locations until there are at least this many readings per unknown (noise averaging).
    double min_readings_per_unknown = 3.0;
    std::size_t max_locations = 40;
};

struct PlannedLocation {
    Pose rotary;  ///< rotary angles (X, Y, Z unused)
    Vec3 socket_mm = Vec3::Zero();
    std::vector<Pose> points;  ///< commanded poses of the tool ball around the table ball
};

struct PlannedParam {
    Param param;
    double independence = 0;  ///< at the plan's end
    bool observable = false;
};

struct IdentificationPlan {
    std::vector<PlannedLocation> locations;
    std::vector<PlannedParam> params;
    /// Parameters that no candidate set can determine (removed from the goal, with the reason).
    std::vector<std::string> unreachable;
    bool sufficient = false;  ///< every reachable parameter reached the target independence
    std::size_t readings() const;
};

/// Throws AnalysisError for an empty candidate set or invalid options.
IdentificationPlan plan_identification(const MachineGeometry& geom, const PlanOptions& options);

/// The readings a plan produces on the nominal machine (measured = nominal bar length), with location
/// and point indices filled in: the template for simulation or for an acquisition NC program.
ReadingSet plan_readings(const MachineGeometry& geom, const IdentificationPlan& plan);

/// The commanded poses of one SSM location: tool ball on a cone about +Z around the table ball.
PlannedLocation ssm_location(const MachineGeometry& geom, const Pose& rotary, const Vec3& socket_mm,
                             double bar_length_mm, double cone_half_angle_rad, int points);

}  // namespace ballbar::analysis
