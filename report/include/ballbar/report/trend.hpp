// SPDX-License-Identifier: MIT
// A machine's trend over months (`ballbar trend MACHINE --out trend.pdf`, docs/fleet.md): every headline
// figure of its sessions against time, each with its uncertainties, its tolerance line and the drift
// found in it. The workflow fills it (from a station's database or the plant's server); this renders it.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace ballbar::report {

struct TrendValue {
    std::string session;     ///< the station's id ("12") or, from the server, the uuid's first 8 characters
    std::string started_at;  ///< ISO 8601
    double t_days = 0;       ///< since the first session of the trend
    double value = 0;
    std::optional<double> value_std;  ///< standard uncertainty (k = 1)
    bool demo = false;
};

struct TrendSeries {
    std::string key;                  ///< "G_XY_um", "backlash_x_um", "d_alpha_arcsec", "X0C_um", …
    std::string label;                ///< "G, XY plane"
    std::string unit;                 ///< for the screen: "µm", "arcsec", "µm/m"
    std::optional<double> tolerance;  ///< |value| allowed (the registered machine file's)
    std::vector<TrendValue> values;   ///< oldest first
    /// The drift: the weighted straight line through the values, per year, with its standard
    /// uncertainty (scaled by the Birge ratio when the values scatter more than their uncertainties say).
    std::optional<double> slope_per_year, slope_per_year_std, intercept;  ///< intercept: at t_days = 0
    std::string flag;    ///< "", "over tolerance", "drifting", "drifting toward tolerance"
    std::string detail;  ///< the flag in words: "+3.1 ± 0.6 µm a year; reaches 12 µm about 2027-03"
};

struct TrendDocument {
    std::string machine;  ///< asset id or label
    std::string source;   ///< "station database /path" or "server database ballbar on db:5432"
    std::string since;    ///< "" or YYYY-MM-DD
    std::string first_at, last_at;
    int sessions = 0;
    std::string generated_at;
    std::string software_version;
    std::vector<TrendSeries> series;
};

/// The trend as a PDF (A4): a summary table (figure, sessions, latest, tolerance, drift, flag), then one
/// plot a figure. Throws ReportError for a trend without a figure.
std::string render_trend_pdf_bytes(const TrendDocument& trend, int* pages = nullptr);

}  // namespace ballbar::report
