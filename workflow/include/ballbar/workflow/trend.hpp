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

#include "ballbar/storage/store.hpp"

namespace ballbar::workflow {

struct TrendPoint {
    std::int64_t session = 0;
    std::string started_at;
    std::string procedure;
    bool demo = false;                      ///< the emulator's session
    std::map<std::string, double> figures;  ///< "G_um", "backlash_x_um", "dV_max_um", "d_alpha_arcsec", …
};

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

}  // namespace ballbar::workflow
