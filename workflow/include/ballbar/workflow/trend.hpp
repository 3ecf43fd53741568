// SPDX-License-Identifier: MIT
// A machine's headline figures across its sessions, oldest first (the web page's trend, `GET
// /api/trend?machine=…`): from each completed session's stored results — a circular test's G (the
// largest of its runs), G(b), backlash X/Y and squareness; an SSM session's largest |ΔV| and its
// orientation errors Δα/Δβ/Δγ (each the mean over the tests that measure it). Units in the names.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "ballbar/acquisition/machine_file.hpp"
#include "ballbar/report/trend.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::workflow {

struct TrendPoint {
    std::int64_t session = 0;
    std::string uuid;
    std::string started_at;
    std::string procedure;
    bool demo = false;                      ///< the emulator's session
    std::map<std::string, double> figures;  ///< "G_um", "backlash_x_um", "dV_max_um", "d_alpha_arcsec", …
    /// Standard uncertainties (k = 1) of the figures that have one, under the same names. Besides the
    /// figures above, the detailed ones `ballbar trend` plots: "G_XY_um" (per plane),
    /// "squareness_XY_um_per_m", and each identified parameter ("X0C_um", "A0C_arcsec", "EXX_um_per_m").
    std::map<std::string, double> uncertainties;
};

/// What a session's figures are computed from, wherever it is stored (a station's database, the server).
struct TrendSessionInput {
    std::int64_t session = 0;  ///< the station's id; 0 on the server
    std::string uuid;
    std::string started_at;
    std::string procedure;
    bool demo = false;
    analysis::MachineType type = analysis::MachineType::TTTRR;
    std::vector<std::pair<std::string, std::string>> results;  ///< (kind, payload) in the order stored
};

/// One session's headline figures and uncertainties from its results (unreadable ones skipped).
TrendPoint session_figures(const TrendSessionInput& session);

/// How a session names its machine in a trend and in the page's filter: "TTTRR mill-1" (type, name).
std::string machine_label(const analysis::MachineGeometry& machine);
/// A session's machine: its asset id when it was measured on a registered machine (`--asset`), else
/// the geometry's label.
std::string machine_label(const storage::SessionInfo& session);

/// One session's headline figures from its stored results (none when it holds no result).
TrendPoint session_figures(storage::Store& store, const storage::SessionInfo& session);

/// The figure a list shows for a session: "G 12.3 µm" (a circular test, the largest of its runs),
/// "|ΔV| max 45.2 µm" (the SSM); empty when it has neither.
std::string headline(const TrendPoint& figures);

/// The completed sessions of the machine labelled `machine` (machine_label) that hold a result, oldest
/// first. A stored result that cannot be read is skipped (its session shows its error on its own page).
std::vector<TrendPoint> machine_trend(storage::Store& store, const std::string& machine);

/// The trend as JSON, as `ballbar sessions trend MACHINE --json` prints it and `GET /api/trend` answers:
/// {"machine", "points": [{"session", "started_at", "procedure", "demo", "figures": {name: value}}]}.
std::string trend_json(const std::string& machine, const std::vector<TrendPoint>& points);

// `ballbar trend MACHINE` (docs/fleet.md): every figure over time, its tolerance, its drift ----------

/// The figures a trend plots, in this order, from the points' figures: G per plane, backlash per axis,
/// squareness per plane, the SSM's largest |ΔV|, Δα/Δβ/Δγ, then the identified parameters. Tolerances:
/// G ← circularity_um, |ΔV| ← location_um, the angles ← angle_arcsec. Each series with its drift.
report::TrendDocument build_trend(const std::string& machine, const std::vector<TrendPoint>& points,
                                  const acquisition::Tolerances& tolerances);

/// Fits the series' straight line (weighted by 1/σ² when every value has an uncertainty; the slope's
/// uncertainty scaled by the Birge ratio when χ²/dof > 1) and sets its flag: "over tolerance" (the last
/// |value| beyond it), "drifting toward tolerance" (|slope| > 3σ and the line reaches it within 182
/// days of the last value), "drifting" (|slope| > 3σ). Needs three values over at least a day; fewer
/// leave the slope empty.
void assess_drift(report::TrendSeries& series, const std::string& first_at);

/// The station's completed sessions of `machine` started on or after `since` (YYYY-MM-DD; "" = all).
std::vector<TrendPoint> machine_trend(storage::Store& store, const std::string& machine, const std::string& since);

/// The whole trend of `machine` (an asset id, or the label of a machine registered nowhere): from the
/// station's database, or with `from_conninfo` from the plant's server (every station's sessions);
/// tolerances from the registered machine file. `store` may be null with a server.
report::TrendDocument machine_trend_document(storage::Store* store, const std::string& machine,
                                             const std::string& since, const std::string& from_conninfo);

/// The trend document as JSON (docs/cli.md's vocabulary): {"machine", "source", "since", "sessions",
/// "first_at", "last_at", "figures": [{"key", "label", "unit", "tolerance", "slope_per_year",
/// "slope_per_year_std", "flag", "detail", "points": [{"session", "started_at", "demo", "value",
/// "value_std"}]}]}.
std::string trend_document_json(const report::TrendDocument& trend);

}  // namespace ballbar::workflow
