// SPDX-License-Identifier: MIT
// Empirical terms: names, the families the search tests, and their Jacobian columns through the
// reading model's gradient.
#include "ballbar/analysis/empirical.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "ballbar/analysis/identify.hpp"
#include "ballbar/analysis/kinematics.hpp"

namespace ballbar::analysis {
namespace {

constexpr double kPositioningRefMm = 100.0;  // δX = c·(X / 100 mm)^k

Param zero_of(char axis) {
    return axis == 'A' ? Param::A_zero : axis == 'B' ? Param::B_zero : Param::C_zero;
}

double angle_of(const Pose& p, char axis) {
    return axis == 'A' ? p.A_rad : axis == 'B' ? p.B_rad : p.C_rad;
}

double linear_of(const Pose& p, char axis) {
    return axis == 'X' ? p.X_mm : axis == 'Y' ? p.Y_mm : p.Z_mm;
}

int dir_index(char d) {
    return d == 'x' ? 0 : d == 'y' ? 1 : 2;
}

bool is_location(Param p) {
    switch (p) {
        case Param::Y0A:
        case Param::Z0A:
        case Param::X0B:
        case Param::Z0B:
        case Param::X0C:
        case Param::Y0C:
            return true;
        default:
            return false;
    }
}

bool varies(const std::vector<double>& v) {
    if (v.empty()) return false;
    const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
    return *hi - *lo > 1e-9;
}

}  // namespace

std::string EmpiricalTerm::name() const {
    const std::string ax(1, axis);
    switch (kind) {
        case EmpiricalKind::rotary_angular:
            return ax + "_angular_h" + std::to_string(order) + (sine ? "_sin" : "_cos");
        case EmpiricalKind::rotary_backlash:
            return ax + "_backlash";
        case EmpiricalKind::linear_positioning:
            return ax + "_positioning_p" + std::to_string(order);
        case EmpiricalKind::location_drift:
            return std::string(param_info(location).name) + "_drift";
        case EmpiricalKind::pivot_drift:
            return "pivot_drift_" + ax;
        case EmpiricalKind::bar_temp_pivot:
            return "bar_temp_pivot_" + ax;
        case EmpiricalKind::air_temp_pivot:
            return "air_temp_pivot_" + ax;
        case EmpiricalKind::bar_temp_quadratic:
            return "bar_temp_quadratic";
        case EmpiricalKind::tool_offset:
            return "tool_offset_" + ax;
    }
    return {};
}

std::string EmpiricalTerm::unit() const {
    switch (kind) {
        case EmpiricalKind::rotary_angular:
        case EmpiricalKind::rotary_backlash:
            return "rad";
        case EmpiricalKind::linear_positioning:
        case EmpiricalKind::tool_offset:
            return "mm";
        case EmpiricalKind::location_drift:
            return param_info(location).unit == ParamUnit::rad ? "rad_per_h" : "mm_per_h";
        case EmpiricalKind::pivot_drift:
            return "mm_per_h";
        case EmpiricalKind::bar_temp_pivot:
        case EmpiricalKind::air_temp_pivot:
            return "mm_per_K";
        case EmpiricalKind::bar_temp_quadratic:
            return "per_K2";
    }
    return {};
}

std::optional<EmpiricalTerm> parse_empirical_term(std::string_view name) {
    auto starts = [&name](std::string_view p) { return name.substr(0, p.size()) == p; };
    auto dir = [](char c) { return c == 'x' || c == 'y' || c == 'z'; };
    EmpiricalTerm t;
    const std::string n(name);
    if (n.size() >= 14 && (n[0] == 'A' || n[0] == 'B' || n[0] == 'C') && n.substr(1, 10) == "_angular_h") {
        const std::string rest = n.substr(11);  // "<k>_cos"
        if (rest.size() == 5 && rest[0] >= '1' && rest[0] <= '9' &&
            (rest.substr(1) == "_cos" || rest.substr(1) == "_sin")) {
            t.kind = EmpiricalKind::rotary_angular;
            t.axis = n[0];
            t.order = rest[0] - '0';
            t.sine = rest.substr(1) == "_sin";
            return t;
        }
        return std::nullopt;
    }
    if (n.size() == 10 && (n[0] == 'A' || n[0] == 'B' || n[0] == 'C') && n.substr(1) == "_backlash") {
        t.kind = EmpiricalKind::rotary_backlash;
        t.axis = n[0];
        return t;
    }
    if (n.size() == 16 && (n[0] == 'X' || n[0] == 'Y' || n[0] == 'Z') && n.substr(1, 14) == "_positioning_p" &&
        n[15] >= '2' && n[15] <= '9') {
        t.kind = EmpiricalKind::linear_positioning;
        t.axis = n[0];
        t.order = n[15] - '0';
        return t;
    }
    if (n.size() > 6 && n.substr(n.size() - 6) == "_drift" && !starts("pivot")) {
        const auto p = parse_param(n.substr(0, n.size() - 6));
        if (!p || !is_location(*p)) return std::nullopt;
        t.kind = EmpiricalKind::location_drift;
        t.location = *p;
        return t;
    }
    struct Prefix {
        std::string_view text;
        EmpiricalKind kind;
    };
    for (const Prefix& p :
         {Prefix{"pivot_drift_", EmpiricalKind::pivot_drift}, Prefix{"bar_temp_pivot_", EmpiricalKind::bar_temp_pivot},
          Prefix{"air_temp_pivot_", EmpiricalKind::air_temp_pivot}, Prefix{"tool_offset_", EmpiricalKind::tool_offset}})
        if (starts(p.text) && name.size() == p.text.size() + 1 && dir(name.back())) {
            t.kind = p.kind;
            t.axis = name.back();
            return t;
        }
    if (name == "bar_temp_quadratic") {
        t.kind = EmpiricalKind::bar_temp_quadratic;
        return t;
    }
    return std::nullopt;
}

std::vector<double> approach_direction(const ReadingSet& readings, char axis) {
    const std::size_t n = readings.readings.size();
    std::vector<std::size_t> order(n);
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return readings.readings[a].time_s < readings.readings[b].time_s;
    });
    std::vector<double> out(n, 0.0);
    double sense = 0;
    double prev = 0;
    bool first = true;
    for (std::size_t i : order) {
        const double a = angle_of(readings.readings[i].pose, axis);
        if (!first && std::abs(a - prev) > 1e-9) sense = a > prev ? 1.0 : -1.0;
        first = false;
        prev = a;
        out[i] = sense;
    }
    return out;
}

std::vector<EmpiricalFamily> empirical_families(const ReadingSet& readings) {
    const MachineType type = readings.machine.type;
    const RotaryAxes ra = rotary_axes(type);
    std::vector<EmpiricalFamily> out;
    auto single_groups = [](EmpiricalFamily& f) {
        for (std::size_t i = 0; i < f.terms.size(); ++i) f.groups.push_back({i});
    };
    for (char ax : {ra.first, ra.second}) {
        EmpiricalFamily f{std::string(1, ax) + "_angular", std::string(1, ax), {}, {}};
        for (int k = 1; k <= 4; ++k) {
            for (bool s : {false, true}) f.terms.push_back({EmpiricalKind::rotary_angular, ax, k, s, Param::X0C});
            f.groups.push_back({f.terms.size() - 2, f.terms.size() - 1});
        }
        out.push_back(std::move(f));
        const std::vector<double> dir = approach_direction(readings, ax);
        if (std::count(dir.begin(), dir.end(), 1.0) > 0 && std::count(dir.begin(), dir.end(), -1.0) > 0) {
            EmpiricalFamily b{std::string(1, ax) + "_backlash", std::string(1, ax) + " approach direction", {}, {}};
            b.terms.push_back({EmpiricalKind::rotary_backlash, ax, 1, false, Param::X0C});
            single_groups(b);
            out.push_back(std::move(b));
        }
    }
    for (char ax : {'X', 'Y', 'Z'}) {
        EmpiricalFamily f{std::string(1, ax) + "_positioning", std::string(1, ax), {}, {}};
        for (int k = 2; k <= 3; ++k) f.terms.push_back({EmpiricalKind::linear_positioning, ax, k, false, Param::X0C});
        single_groups(f);
        out.push_back(std::move(f));
    }
    std::vector<double> time, bar, air;
    bool has_air = !readings.readings.empty();
    for (const Reading& r : readings.readings) {
        time.push_back(r.time_s);
        bar.push_back(r.bar_temp_C.value_or(20.0));
        has_air = has_air && r.air_temp_C.has_value();
        air.push_back(r.air_temp_C.value_or(20.0));
    }
    if (varies(time)) {
        EmpiricalFamily f{"time", "time", {}, {}};
        for (Param p : rotary_params_for(type))
            if (is_location(p)) f.terms.push_back({EmpiricalKind::location_drift, 'x', 1, false, p});
        for (char d : {'x', 'y'}) f.terms.push_back({EmpiricalKind::pivot_drift, d, 1, false, Param::X0C});
        single_groups(f);
        out.push_back(std::move(f));
    }
    if (varies(bar)) {
        EmpiricalFamily f{"bar_temperature", "bar temperature", {}, {}};
        f.terms.push_back({EmpiricalKind::bar_temp_quadratic, 'x', 2, false, Param::X0C});
        for (char d : {'x', 'y', 'z'}) f.terms.push_back({EmpiricalKind::bar_temp_pivot, d, 1, false, Param::X0C});
        single_groups(f);
        out.push_back(std::move(f));
    }
    if (has_air && varies(air)) {
        EmpiricalFamily f{"air_temperature", "air temperature", {}, {}};
        for (char d : {'x', 'y', 'z'}) f.terms.push_back({EmpiricalKind::air_temp_pivot, d, 1, false, Param::X0C});
        single_groups(f);
        out.push_back(std::move(f));
    }
    EmpiricalFamily f{"bar_direction", "bar direction", {}, {}};
    for (char d : {'x', 'y', 'z'}) f.terms.push_back({EmpiricalKind::tool_offset, d, 0, false, Param::X0C});
    single_groups(f);
    out.push_back(std::move(f));
    return out;
}

TermBasis term_basis(const ReadingSet& readings, const ErrorParams& e, std::span<const Vec3> socket_offsets_mm) {
    TermBasis b;
    b.grad_params = rotary_params_for(readings.machine.type);
    b.grad = reading_jacobian(readings, e, b.grad_params, socket_offsets_mm, false);
    const auto n = static_cast<Eigen::Index>(readings.readings.size());
    b.u.resize(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) {
        const Reading& r = readings.readings[static_cast<std::size_t>(i)];
        const BallCentres c = nominal_balls(readings.machine, r.pose, r.socket_mm);
        Vec3 u = c.tool - c.table;
        const double len = u.norm();
        if (len > 0) u /= len;
        b.u.row(i) = u.transpose();
    }
    const RotaryAxes ra = rotary_axes(readings.machine.type);
    for (char ax : {ra.first, ra.second}) {
        std::vector<double> d = approach_direction(readings, ax);
        (ax == 'A' ? b.dir_a : ax == 'B' ? b.dir_b : b.dir_c) = std::move(d);
    }
    return b;
}

Eigen::VectorXd term_column(const ReadingSet& readings, const TermBasis& basis, const EmpiricalTerm& t) {
    const auto n = static_cast<Eigen::Index>(readings.readings.size());
    Eigen::VectorXd col = Eigen::VectorXd::Zero(n);
    auto grad_col = [&basis](Param p) -> Eigen::Index {
        const auto it = std::find(basis.grad_params.begin(), basis.grad_params.end(), p);
        return it == basis.grad_params.end() ? -1 : static_cast<Eigen::Index>(it - basis.grad_params.begin());
    };
    const Eigen::Index gz = grad_col(zero_of(t.axis));
    const Eigen::Index gl = grad_col(t.location);
    const std::vector<double>& dir = t.axis == 'A' ? basis.dir_a : t.axis == 'B' ? basis.dir_b : basis.dir_c;
    for (Eigen::Index i = 0; i < n; ++i) {
        const Reading& r = readings.readings[static_cast<std::size_t>(i)];
        double v = 0;
        switch (t.kind) {
            case EmpiricalKind::rotary_angular: {
                if (gz < 0) break;
                const double k_theta = t.order * angle_of(r.pose, t.axis);
                v = basis.grad(i, gz) * (t.sine ? std::sin(k_theta) : std::cos(k_theta));
                break;
            }
            case EmpiricalKind::rotary_backlash:
                if (gz >= 0 && !dir.empty()) v = basis.grad(i, gz) * dir[static_cast<std::size_t>(i)];
                break;
            case EmpiricalKind::linear_positioning:
                v = basis.u(i, dir_index(static_cast<char>(t.axis - 'X' + 'x'))) *
                    std::pow(linear_of(r.pose, t.axis) / kPositioningRefMm, t.order);
                break;
            case EmpiricalKind::location_drift:
                if (gl >= 0) v = basis.grad(i, gl) * r.time_s / 3600.0;
                break;
            case EmpiricalKind::pivot_drift:
                v = basis.u(i, dir_index(t.axis)) * r.time_s / 3600.0;
                break;
            case EmpiricalKind::bar_temp_pivot:
                v = basis.u(i, dir_index(t.axis)) * (r.bar_temp_C.value_or(20.0) - 20.0);
                break;
            case EmpiricalKind::air_temp_pivot:
                v = basis.u(i, dir_index(t.axis)) * (r.air_temp_C.value_or(20.0) - 20.0);
                break;
            case EmpiricalKind::bar_temp_quadratic: {
                const double dt = r.bar_temp_C.value_or(20.0) - 20.0;
                v = r.measured_mm * dt * dt;
                break;
            }
            case EmpiricalKind::tool_offset:
                v = basis.u(i, dir_index(t.axis));
                break;
        }
        col[i] = v;
    }
    return col;
}

double rotary_angle_error(std::span<const LearnedTerm> terms, char axis, double angle_rad, double approach) {
    double eps = 0;
    for (const LearnedTerm& l : terms) {
        if (l.term.axis != axis) continue;
        if (l.term.kind == EmpiricalKind::rotary_angular)
            eps += l.value * (l.term.sine ? std::sin(l.term.order * angle_rad) : std::cos(l.term.order * angle_rad));
        else if (l.term.kind == EmpiricalKind::rotary_backlash)
            eps += l.value * approach;
    }
    return eps;
}

double linear_positioning_error(std::span<const LearnedTerm> terms, char axis, double position_mm) {
    double d = 0;
    for (const LearnedTerm& l : terms)
        if (l.term.kind == EmpiricalKind::linear_positioning && l.term.axis == axis)
            d += l.value * std::pow(position_mm / kPositioningRefMm, l.term.order);
    return d;
}

Eigen::VectorXd empirical_contribution(const ReadingSet& readings, const TermBasis& basis,
                                       std::span<const LearnedTerm> terms) {
    Eigen::VectorXd c = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(readings.readings.size()));
    for (const LearnedTerm& l : terms) c += l.value * term_column(readings, basis, l.term);
    return c;
}

}  // namespace ballbar::analysis
