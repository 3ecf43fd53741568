// SPDX-License-Identifier: MIT
// The machine file (`ballbar-machine/1`, JSON): the nominal geometry with the keys of the readings
// file's `machine` header, the axis travel limits, the NC dialect, the feed used for measuring moves and
// the tolerances the results are judged against.
// docs/procedure.md documents the format.
#pragma once

#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "ballbar/analysis/nc_program.hpp"
#include "ballbar/analysis/types.hpp"

namespace ballbar::acquisition {

/// Malformed machine or plan file, or a plan the machine cannot run. The message names the key or the
/// point and the problem.
class PlanError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// Axis indices of travel limits: X, Y, Z in mm, A, B, C in radians.
enum class Axis { X, Y, Z, A, B, C };
constexpr int kAxisCount = 6;
std::string_view axis_name(Axis a);  // "X", ...

struct AxisRange {
    double min = -1e9;
    double max = 1e9;
};

/// What the shop allows of this machine, for pass/fail verdicts (none given: no verdict). SSM: a
/// location passes when |ΔV| ≤ location_um, an orientation error when |Δα|, |Δβ| or |Δγ| ≤ angle_arcsec;
/// circular: a run passes when G ≤ circularity_um (ISO 230-4's circular deviation).
struct Tolerances {
    std::optional<double> location_um;
    std::optional<double> angle_arcsec;
    std::optional<double> circularity_um;
    bool any() const { return location_um || angle_arcsec || circularity_um; }
};

struct MachineFile {
    analysis::MachineGeometry geometry;
    std::array<AxisRange, kAxisCount> travel{};  ///< unlimited unless the file says otherwise
    analysis::NcDialect dialect = analysis::NcDialect::Fanuc;
    double feed_mm_min = 1000;  ///< feed of the measuring moves (G1)
    Tolerances tolerances;

    const AxisRange& range(Axis a) const { return travel[static_cast<std::size_t>(a)]; }
};

/// Parses a machine file's text. Throws PlanError naming the key.
MachineFile parse_machine_file(std::string_view json_text);
/// Writes the same format back.
std::string write_machine_file(const MachineFile& machine);

}  // namespace ballbar::acquisition

namespace ballbar::acquisition {
/// A machine of `type` with the seeds' geometry (RRTTT: Table 1's 250 mm tool; TTTRR: Table 2's
/// z_αγ = −100 mm; RTTTR: a 150 mm tool and the A axis 200 mm below the origin) and generous travel.
MachineFile seed_machine(analysis::MachineType type);
}  // namespace ballbar::acquisition
