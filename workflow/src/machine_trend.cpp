// SPDX-License-Identifier: MIT
// `ballbar trend`: the series of a machine's figures, their drift and their JSON (docs/fleet.md).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <nlohmann/json.hpp>

#include "ballbar/fleet/server_read.hpp"
#include "ballbar/workflow/machines.hpp"
#include "ballbar/workflow/trend.hpp"

namespace ballbar::workflow {
namespace {

/// Seconds since the epoch of an ISO 8601 UTC time ("2026-12-06T06:17:05.123Z"); 0 when unreadable.
double epoch_s(const std::string& iso) {
    std::tm tm{};
    int ms = 0;
    if (std::sscanf(iso.c_str(), "%d-%d-%dT%d:%d:%d.%d", &tm.tm_year, &tm.tm_mon, &tm.tm_mday, &tm.tm_hour, &tm.tm_min,
                    &tm.tm_sec, &ms) < 3)
        return 0;
    tm.tm_year -= 1900;
    tm.tm_mon -= 1;
    return static_cast<double>(timegm(&tm)) + ms / 1000.0;
}

std::string month_of(double epoch) {
    const std::time_t t = static_cast<std::time_t>(epoch);
    std::tm tm{};
    gmtime_r(&t, &tm);
    char b[32];
    std::snprintf(b, sizeof b, "%04d-%02d", tm.tm_year + 1900, tm.tm_mon + 1);
    return b;
}

struct Kind {
    std::string label, unit;
    std::optional<double> tolerance;
    int order = 0;
};

/// What a figure's key is, for the trend (empty label: not plotted).
Kind kind_of(const std::string& key, const acquisition::Tolerances& tol) {
    auto ends = [&](const char* s) { return key.ends_with(s); };
    if (key.size() == 7 && key.starts_with("G_") && ends("_um"))  // G_XY_um
        return {"G, " + key.substr(2, 2) + " plane", "µm", tol.circularity_um, 0};
    if (key.starts_with("backlash_"))
        return {"backlash " + std::string(1, static_cast<char>(std::toupper(key[9]))), "µm", {}, 1};
    if (key.starts_with("squareness_") && key.size() > 24)
        return {"squareness, " + key.substr(11, 2) + " plane", "µm/m", {}, 2};
    if (key == "dV_max_um") return {"SSM |ΔV| largest", "µm", tol.location_um, 3};
    if (key == "d_alpha_arcsec") return {"Δα", "arcsec", tol.angle_arcsec, 4};
    if (key == "d_beta_arcsec") return {"Δβ", "arcsec", tol.angle_arcsec, 5};
    if (key == "d_gamma_arcsec") return {"Δγ", "arcsec", tol.angle_arcsec, 6};
    if (key == "G_um" || key == "G_b_um" || key == "H_um" || key == "squareness_um_per_m") return {};  // the page's
    const auto us = key.find('_');
    if (us == std::string::npos) return {};
    const std::string unit = key.substr(us + 1);
    const std::string screen = unit == "um" ? "µm" : unit == "um_per_m" ? "µm/m" : unit == "arcsec" ? "arcsec" : "";
    if (screen.empty()) return {};
    return {key.substr(0, us) + " (identified)", screen, {}, 7};
}

std::string json_unit(const std::string& key) {
    if (key.ends_with("_um_per_m")) return "um_per_m";
    if (key.ends_with("_arcsec")) return "arcsec";
    return "um";
}

std::string signed_text(double v) {
    char b[48];
    std::snprintf(b, sizeof b, "%+.2f", v);
    return b;
}

}  // namespace

void assess_drift(report::TrendSeries& s, const std::string& first_at) {
    s.slope_per_year.reset();
    s.slope_per_year_std.reset();
    s.intercept.reset();
    s.flag.clear();
    s.detail.clear();
    if (s.values.empty()) return;
    const auto& last = s.values.back();
    const std::size_t n = s.values.size();
    const double span = s.values.back().t_days - s.values.front().t_days;
    if (n >= 3 && span >= 1) {
        const bool weighted = std::all_of(s.values.begin(), s.values.end(),
                                          [](const auto& v) { return v.value_std && *v.value_std > 0; });
        double sw = 0, st = 0, sy = 0;
        for (const auto& v : s.values) {
            const double w = weighted ? 1 / (*v.value_std * *v.value_std) : 1;
            sw += w, st += w * v.t_days, sy += w * v.value;
        }
        const double tm = st / sw, ym = sy / sw;
        double sxx = 0, sxy = 0;
        for (const auto& v : s.values) {
            const double w = weighted ? 1 / (*v.value_std * *v.value_std) : 1;
            sxx += w * (v.t_days - tm) * (v.t_days - tm);
            sxy += w * (v.t_days - tm) * (v.value - ym);
        }
        const double k = sxy / sxx;  // per day
        double chi2 = 0;
        for (const auto& v : s.values) {
            const double w = weighted ? 1 / (*v.value_std * *v.value_std) : 1;
            const double r = v.value - (ym + k * (v.t_days - tm));
            chi2 += w * r * r;
        }
        const double dof = static_cast<double>(n - 2);
        double k_std = weighted ? 1 / std::sqrt(sxx) : std::sqrt(chi2 / dof / sxx);
        if (weighted && chi2 / dof > 1) k_std *= std::sqrt(chi2 / dof);  // the Birge ratio
        s.slope_per_year = k * 365.25;
        s.slope_per_year_std = k_std * 365.25;
        s.intercept = ym - k * tm;
    }
    const std::string unit = " " + s.unit;
    if (s.tolerance && std::abs(last.value) > *s.tolerance) {
        s.flag = "over tolerance";
        s.detail = "latest " + signed_text(last.value) + unit + " (session " + last.session +
                   ") is beyond the tolerance ±" + signed_text(*s.tolerance).substr(1) + unit;
        return;
    }
    if (!s.slope_per_year) return;
    const double k = *s.slope_per_year, k_std = *s.slope_per_year_std;
    if (!(std::abs(k) > 3 * k_std)) return;
    const std::string rate = signed_text(k) + " ± " + signed_text(k_std).substr(1) + unit + " a year";
    s.flag = "drifting";
    s.detail = rate + " (more than 3 standard uncertainties from zero)";
    if (s.tolerance && k != 0) {
        const double target = k > 0 ? *s.tolerance : -*s.tolerance;
        const double t_hit = (target - *s.intercept) / (k / 365.25);
        if (t_hit >= last.t_days && t_hit - last.t_days <= 182.6) {
            s.flag = "drifting toward tolerance";
            s.detail = rate + "; the line reaches ±" + signed_text(*s.tolerance).substr(1) + unit + " about " +
                       month_of(epoch_s(first_at) + t_hit * 86400);
        }
    }
}

std::vector<TrendPoint> machine_trend(storage::Store& store, const std::string& machine, const std::string& since) {
    auto points = machine_trend(store, machine);
    std::erase_if(points, [&](const TrendPoint& p) { return !since.empty() && p.started_at < since; });
    return points;
}

report::TrendDocument build_trend(const std::string& machine, const std::vector<TrendPoint>& points,
                                  const acquisition::Tolerances& tolerances) {
    report::TrendDocument t;
    t.machine = machine;
    t.sessions = static_cast<int>(points.size());
    if (points.empty()) return t;
    t.first_at = points.front().started_at;
    t.last_at = points.back().started_at;
    const double t0 = epoch_s(t.first_at);
    std::map<std::string, report::TrendSeries> by_key;
    std::map<std::string, int> order;
    for (const auto& p : points) {
        for (const auto& [key, value] : p.figures) {
            const Kind kind = kind_of(key, tolerances);
            if (kind.label.empty() || !std::isfinite(value)) continue;
            auto& s = by_key[key];
            if (s.key.empty()) {
                s.key = key, s.label = kind.label, s.unit = kind.unit, s.tolerance = kind.tolerance;
                order[key] = kind.order;
            }
            report::TrendValue v;
            v.session = p.session ? std::to_string(p.session) : p.uuid.substr(0, 8);
            v.started_at = p.started_at;
            v.t_days = (epoch_s(p.started_at) - t0) / 86400;
            v.value = value;
            if (const auto u = p.uncertainties.find(key); u != p.uncertainties.end()) v.value_std = u->second;
            v.demo = p.demo;
            s.values.push_back(v);
        }
    }
    for (auto& [key, s] : by_key) {
        assess_drift(s, t.first_at);
        t.series.push_back(std::move(s));
    }
    std::stable_sort(t.series.begin(), t.series.end(), [&](const auto& a, const auto& b) {
        return order[a.key] != order[b.key] ? order[a.key] < order[b.key] : a.key < b.key;
    });
    return t;
}

report::TrendDocument machine_trend_document(storage::Store* store, const std::string& machine,
                                             const std::string& since, const std::string& from_conninfo) {
    std::vector<TrendPoint> points;
    acquisition::Tolerances tolerances;
    std::string source;
    if (!from_conninfo.empty()) {
        fleet::pg::Connection c(from_conninfo);
        source = "server " + c.where();
        for (auto& s : fleet::server_machine_sessions(c, machine, since)) {
            TrendSessionInput in;
            in.uuid = s.uuid;
            in.started_at = s.started_at;
            in.procedure = s.procedure;
            in.demo = s.source == "emulator";
            in.type = analysis::parse_machine_type(s.machine_type).value_or(analysis::MachineType::TTTRR);
            in.results = std::move(s.results);
            TrendPoint p = session_figures(in);
            if (!p.figures.empty()) points.push_back(std::move(p));
        }
        if (const std::string file = fleet::server_machine_file(c, machine); !file.empty()) {
            try {
                tolerances = acquisition::parse_machine_file(file).tolerances;
            } catch (const std::exception&) {  // a machine file of a newer format: the trend without tolerances
            }
        }
    } else {
        source = "station " + store->path();
        points = machine_trend(*store, machine, since);
        for (const auto& m : store->machines())
            if (m.asset_id == machine) tolerances = registered_machine_file(*store, machine).tolerances;
    }
    report::TrendDocument t = build_trend(machine, points, tolerances);
    t.source = source;
    t.since = since;
    t.software_version = BALLBAR_VERSION;
    return t;
}

std::string trend_document_json(const report::TrendDocument& t) {
    using J = nlohmann::ordered_json;
    auto opt = [](const std::optional<double>& v) { return v ? J(*v) : J(nullptr); };
    auto text = [](const std::string& s) { return s.empty() ? J(nullptr) : J(s); };
    J figures = J::array();
    for (const auto& s : t.series) {
        J points = J::array();
        for (const auto& v : s.values)
            points.push_back({{"session", v.session},
                              {"started_at", v.started_at},
                              {"demo", v.demo},
                              {"value", v.value},
                              {"value_std", opt(v.value_std)}});
        figures.push_back({{"key", s.key},
                           {"label", s.label},
                           {"unit", json_unit(s.key)},
                           {"tolerance", opt(s.tolerance)},
                           {"slope_per_year", opt(s.slope_per_year)},
                           {"slope_per_year_std", opt(s.slope_per_year_std)},
                           {"flag", text(s.flag)},
                           {"detail", text(s.detail)},
                           {"points", points}});
    }
    J j = {{"machine", t.machine},   {"source", text(t.source)},     {"since", text(t.since)},
           {"sessions", t.sessions}, {"first_at", text(t.first_at)}, {"last_at", text(t.last_at)},
           {"figures", figures}};
    return j.dump(2);
}

}  // namespace ballbar::workflow
