// SPDX-License-Identifier: MIT
// The JSON services of `ballbar solve`: a strict reading of the request (fileio::JsonFields: every
// field's type and documented range, unknown keys refused, each error naming its field), the solver,
// and the answer in docs/cli.md's vocabulary (units in the keys, null for what is not there).
#include "ballbar/workflow/solve.hpp"

#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ballbar/analysis/compensate.hpp"
#include "ballbar/analysis/lei_hsu.hpp"
#include "ballbar/analysis/limits.hpp"
#include "ballbar/analysis/orientation.hpp"
#include "ballbar/analysis/ssm.hpp"
#include "ballbar/fileio/json_fields.hpp"

namespace ballbar::workflow {
namespace {

namespace ba = ballbar::analysis;
namespace lim = ballbar::analysis::limits;
using nlohmann::json;

struct Refuse {
    void operator()(const std::string& field, const std::string& problem) const { throw SolveError(problem, field); }
};
using Fields = fileio::JsonFields<json, Refuse>;

std::string index(const std::string& path, std::size_t i) {
    return path + "[" + std::to_string(i) + "]";
}
double number(const json& j, const std::string& field) {
    if (!j.is_number()) throw SolveError("must be a number", field);
    const double v = j.get<double>();
    if (!std::isfinite(v)) throw SolveError("must be finite", field);
    return v;
}
std::vector<double> numbers(const json& j, const std::string& field) {
    if (!j.is_array()) throw SolveError("must be an array of numbers", field);
    std::vector<double> out;
    for (std::size_t i = 0; i < j.size(); ++i) out.push_back(number(j[i], index(field, i)));
    return out;
}
ba::Vec3 vec3(const json& j, const std::string& field) {
    if (!j.is_array() || j.size() != 3) throw SolveError("must be an array of 3 numbers [x, y, z]", field);
    return {number(j[0], index(field, 0)), number(j[1], index(field, 1)), number(j[2], index(field, 2))};
}
/// A required field: missing and null are both "missing".
const json& required(const Fields& f, const char* key) {
    if (const json* v = f.optional(key)) return *v;
    throw SolveError("missing", f.path(key));
}
/// The documented range of a request's value (docs/analysis.md, "Ranges"), or SolveError naming it.
double within_range(double v, const std::string& field, double lo, double hi, const char* unit) {
    if (const std::string why = lim::check_in(v, lo, hi, unit); !why.empty()) throw SolveError(why, field);
    return v;
}
ba::Vec3 within_range(const ba::Vec3& v, const std::string& field, double limit, const char* unit) {
    for (std::size_t i = 0; i < 3; ++i) within_range(v[static_cast<int>(i)], index(field, i), -limit, limit, unit);
    return v;
}
/// A position (socket, pivot, point) and a small length error (ΔV, Δl): ±100 m and ±10 mm.
ba::Vec3 position(const Fields& f, const char* key) {
    return within_range(vec3(required(f, key), f.path(key)), f.path(key), lim::kPosition_mm, "mm");
}
ba::Vec3 length_error(const Fields& f, const char* key) {
    return within_range(vec3(required(f, key), f.path(key)), f.path(key), lim::kSmallLength_mm, "mm");
}
/// A test's rotation, rad: at most one turn each way.
double rotation(const Fields& f, const char* key) {
    const double turn = ba::deg_to_rad(lim::kRotation_deg);
    return within_range(number(required(f, key), f.path(key)), f.path(key), -turn, turn, "rad");
}
/// [0, 0, z] fields of the seed's models: x and y must be zero.
double axial(const Fields& f, const char* key, const char* why) {
    const ba::Vec3 v = position(f, key);
    for (std::size_t i = 0; i < 2; ++i)
        if (v[static_cast<int>(i)] != 0.0) throw SolveError(std::string("must be 0: ") + why, index(f.path(key), i));
    return v.z();
}
json vec_json(const ba::Vec3& v) {
    return json::array({v.x(), v.y(), v.z()});
}

// ---- ssm

json solve_ssm(const json& request) {
    const Fields req(request, "", Refuse{});
    req.only({"socket_mm", "points_mm", "delta_l_mm", "std_mm", "nominal_mm", "max_condition"});
    const ba::Vec3 socket = position(req, "socket_mm");
    const json& jp = required(req, "points_mm");
    if (!jp.is_array()) throw SolveError("must be an array of [x, y, z] points", "points_mm");
    std::vector<ba::Vec3> points;
    for (std::size_t i = 0; i < jp.size(); ++i) {
        const std::string field = index("points_mm", i);
        points.push_back(within_range(vec3(jp[i], field), field, lim::kPosition_mm, "mm"));
        if ((points.back() - socket).norm() < 1e-6) throw SolveError("coincides with the socket", field);
    }
    if (points.size() < 3)
        throw SolveError("SSM needs at least 3 points, got " + std::to_string(points.size()), "points_mm");
    const auto one_per_point = [&](const std::vector<double>& v, const char* field) {
        if (v.size() != points.size())
            throw SolveError(
                "has " + std::to_string(v.size()) + " entries for " + std::to_string(points.size()) + " points", field);
    };
    const std::vector<double> dl = numbers(required(req, "delta_l_mm"), "delta_l_mm");
    for (std::size_t i = 0; i < dl.size(); ++i)
        within_range(dl[i], index("delta_l_mm", i), -lim::kSmallLength_mm, lim::kSmallLength_mm, "mm");
    one_per_point(dl, "delta_l_mm");
    std::vector<double> nominal;
    if (const json* jn = req.optional("nominal_mm")) {
        nominal = numbers(*jn, "nominal_mm");
        one_per_point(nominal, "nominal_mm");
        for (std::size_t i = 0; i < nominal.size(); ++i)
            if (const std::string why = lim::check_above(nominal[i], 0, lim::kLength_mm, "mm"); !why.empty())
                throw SolveError(why, index("nominal_mm", i));
    }
    ba::SsmOptions opt;
    if (const json* js = req.optional("std_mm"))
        opt.reading_std_mm = within_range(number(*js, "std_mm"), "std_mm", 0, lim::kSmallLength_mm, "mm");
    if (const json* jc = req.optional("max_condition"))
        opt.max_condition = within_range(number(*jc, "max_condition"), "max_condition", 1, 1e12, "");
    // The layout's conditioning is the points' fault; anything the solver refuses after that, the readings'.
    const char* blamed = ba::ssm_condition_number(socket, points) <= opt.max_condition ? "delta_l_mm" : "points_mm";
    ba::SsmResult r;
    try {
        r = ba::solve_ssm(socket, points, dl, nominal, opt);
    } catch (const ba::AnalysisError& e) {
        throw SolveError(e.what(), blamed);
    }
    json out;
    out["linear_mm"] = vec_json(r.linear_mm);
    out["exact_mm"] = vec_json(r.exact_mm);
    out["condition_number"] = r.condition_number;
    out["exact_mm_std"] = vec_json(r.std_mm);  // its standard uncertainty (docs/cli.md: K_std)
    out["residual_rms_mm"] = r.residual_rms_mm ? json(*r.residual_rms_mm) : json(nullptr);
    out["reading_sd_mm"] = opt.reading_std_mm;  // the readings' spread the request gave (std_mm)
    out["iterations"] = r.iterations;
    return out;
}

// ---- orientation

/// The angles a solver fills, as JSON keys.
struct Angles {
    bool alpha = false, beta = false, gamma = false;
};

json angles_json(const ba::OrientationErrors& e, Angles which) {
    json out = json::object();
    if (which.alpha) out["d_alpha_rad"] = e.d_alpha_rad;
    if (which.beta) out["d_beta_rad"] = e.d_beta_rad;
    if (which.gamma) out["d_gamma_rad"] = e.d_gamma_rad;
    return out;
}

json solution_json(const ba::OrientationSolution& s, Angles which) {
    json out;
    out["first_order"] = s.first_order ? angles_json(*s.first_order, which) : json(nullptr);
    out["exact"] = s.exact ? angles_json(*s.exact, which) : json(nullptr);
    out["nominal_after_mm"] = vec_json(s.nominal_after_mm);
    out["exact_residual_mm"] = s.exact ? json(s.exact_residual_mm) : json(nullptr);
    out["singular"] = s.singular.empty() ? json(nullptr) : json(s.singular);
    return out;
}

constexpr const char* kOnSpindleAxis = "the seed's model has the tool ball on the spindle axis";

ba::OrientationSolution rtttr_spindle(const json& j) {
    const Fields f(j, "spindle", Refuse{});
    f.only({"pivot_mm", "tool_ball_mm", "beta_rad", "dV1_mm", "dV2_mm"});
    ba::RtttrSpindleInput in;
    in.pivot_mm = position(f, "pivot_mm");
    in.z_r_mm = axial(f, "tool_ball_mm", kOnSpindleAxis);
    in.beta_rad = rotation(f, "beta_rad");
    in.dV1_mm = length_error(f, "dV1_mm");
    in.dV2_mm = length_error(f, "dV2_mm");
    return ba::solve_orientation(in);
}

ba::OrientationSolution rtttr_table(const json& j) {
    const Fields f(j, "table", Refuse{});
    f.only({"a_pivot_mm", "socket_mm", "alpha_rad", "dV1_mm", "dV2_mm"});
    ba::RtttrTableInput in;
    in.a_pivot_mm = position(f, "a_pivot_mm");
    in.socket_mm = position(f, "socket_mm");
    in.alpha_rad = rotation(f, "alpha_rad");
    in.dV1_mm = length_error(f, "dV1_mm");
    in.dV2_mm = length_error(f, "dV2_mm");
    return ba::solve_orientation(in);
}

json solve_rtttr(const Fields& req) {
    req.only({"machine", "spindle", "table"});
    const json* js = req.optional("spindle");
    const json* jt = req.optional("table");
    if (!js && !jt) throw SolveError("give a spindle part, a table part, or both", "spindle");
    std::optional<ba::OrientationSolution> s, t;
    if (js) s = rtttr_spindle(*js);
    if (jt) t = rtttr_table(*jt);
    // Merge: d_beta_rad from the spindle part, d_alpha_rad from the table part.
    auto merge = [&](auto member) -> json {
        json o = json::object();
        bool any = false;
        if (s) {
            o["d_beta_rad"] = ((*s).*member) ? json(((*s).*member)->d_beta_rad) : json(nullptr);
            any = any || ((*s).*member).has_value();
        }
        if (t) {
            o["d_alpha_rad"] = ((*t).*member) ? json(((*t).*member)->d_alpha_rad) : json(nullptr);
            any = any || ((*t).*member).has_value();
        }
        return any ? o : json(nullptr);
    };
    json out;
    out["first_order"] = merge(&ba::OrientationSolution::first_order);
    out["exact"] = merge(&ba::OrientationSolution::exact);
    out["nominal_after_mm"] = json::object();
    std::string singular;
    if (s) {
        out["nominal_after_mm"]["spindle"] = vec_json(s->nominal_after_mm);
        if (!s->singular.empty()) singular = "spindle: " + s->singular;
    }
    if (t) {
        out["nominal_after_mm"]["table"] = vec_json(t->nominal_after_mm);
        if (!t->singular.empty()) singular += (singular.empty() ? "" : "; ") + std::string("table: ") + t->singular;
    }
    out["singular"] = singular.empty() ? json(nullptr) : json(singular);
    return out;
}

json solve_orientation(const json& request) {
    const Fields req(request, "", Refuse{});
    const json& jm = required(req, "machine");
    const auto type = jm.is_string() ? ba::parse_machine_type(jm.get<std::string>()) : std::nullopt;
    if (!type) throw SolveError("must be \"RRTTT\", \"TTTRR\" or \"RTTTR\"", "machine");
    switch (*type) {
        case ba::MachineType::RRTTT: {
            req.only({"machine", "pivot_mm", "tool_ball_mm", "alpha_rad", "beta_rad", "dV1_mm", "dV2_mm"});
            ba::RrtttInput in;
            in.pivot_mm = position(req, "pivot_mm");
            in.z_r_mm = axial(req, "tool_ball_mm", kOnSpindleAxis);
            in.alpha_rad = rotation(req, "alpha_rad");
            in.beta_rad = rotation(req, "beta_rad");
            in.dV1_mm = length_error(req, "dV1_mm");
            in.dV2_mm = length_error(req, "dV2_mm");
            return solution_json(ba::solve_orientation(in), {true, true, false});
        }
        case ba::MachineType::TTTRR: {
            req.only(
                {"machine", "a_pivot_mm", "c_offset_mm", "socket_mm", "alpha_rad", "gamma_rad", "dV1_mm", "dV2_mm"});
            ba::TtttrrInput in;
            in.a_pivot_mm = position(req, "a_pivot_mm");
            in.z_ag_mm = axial(req, "c_offset_mm", "the seed's model has the C axis meet the A axis");
            in.socket_mm = position(req, "socket_mm");
            in.alpha_rad = rotation(req, "alpha_rad");
            in.gamma_rad = rotation(req, "gamma_rad");
            in.dV1_mm = length_error(req, "dV1_mm");
            in.dV2_mm = length_error(req, "dV2_mm");
            return solution_json(ba::solve_orientation(in), {true, false, true});
        }
        case ba::MachineType::RTTTR:
            return solve_rtttr(req);
    }
    throw SolveError("unsupported machine type", "machine");
}

// ---- compensate (Lei & Hsu)

template <int N>
Eigen::Matrix<double, N, 1> fixed_array(const Fields& req, const char* key, const char* shape) {
    const json& v = required(req, key);
    if (!v.is_array() || v.size() != static_cast<std::size_t>(N))
        throw SolveError(std::string("must be an array of ") + std::to_string(N) + " numbers " + shape, key);
    Eigen::Matrix<double, N, 1> out;
    for (int i = 0; i < N; ++i)
        out[i] = number(v[static_cast<std::size_t>(i)], index(key, static_cast<std::size_t>(i)));
    return out;
}

json solve_compensate(const json& request) {
    const Fields req(request, "", Refuse{});
    req.only({"kinematics", "offsets_mm", "u", "dv", "singular_tolerance"});
    const json& kin = required(req, "kinematics");
    if (!kin.is_string() || kin.get<std::string>() != "lei-hsu")
        throw SolveError("must be \"lei-hsu\" (the X'Y'ZA'C' machine of Lei & Hsu)", "kinematics");
    ba::LeiHsuOffsets off;
    if (const json* o = req.optional("offsets_mm")) {
        if (!o->is_object()) throw SolveError("must be an object {\"Xw0\", \"Yw0\", \"Zw0\", \"Z3\"}", "offsets_mm");
        const Fields f(*o, "offsets_mm", Refuse{});
        f.only({"Xw0", "Yw0", "Zw0", "Z3"});
        const auto offset = [&](const char* key, double& out) {
            if (const json* v = f.optional(key))
                out = within_range(number(*v, f.path(key)), f.path(key), -lim::kPosition_mm, lim::kPosition_mm, "mm");
        };
        offset("Xw0", off.Xw0_mm);
        offset("Yw0", off.Yw0_mm);
        offset("Zw0", off.Zw0_mm);
        offset("Z3", off.Z3_mm);
    }
    // The same default as `ballbar compensate --singular-deg` (0.06°): a tolerance of 1e-9 let dθc
    // grow to 1/sin(θa) ≈ 1e9 × the direction error near θa = 0.
    double tol = ba::default_singular_tolerance();
    if (const json* t = req.optional("singular_tolerance")) {
        tol = number(*t, "singular_tolerance");
        if (tol < 0 || tol >= 1) throw SolveError("must be in [0, 1)", "singular_tolerance");
    }
    const ba::Vec5 u = fixed_array<5>(req, "u", "[x_m, y_m, z_m, theta_a_rad, theta_c_rad]");
    const ba::Vec6 dv = fixed_array<6>(req, "dv", "[dx, dy, dz, di, dj, dk]");
    const double turns = ba::deg_to_rad(lim::kRotary_deg);
    for (std::size_t i = 0; i < 5; ++i)
        within_range(u[static_cast<int>(i)], index("u", i), i < 3 ? -lim::kPosition_mm : -turns,
                     i < 3 ? lim::kPosition_mm : turns, i < 3 ? "mm" : "rad");
    for (std::size_t i = 0; i < 6; ++i)  // a pose error: mm, and the change of a unit direction
        within_range(dv[static_cast<int>(i)], index("dv", i), i < 3 ? -lim::kSmallLength_mm : -1.0,
                     i < 3 ? lim::kSmallLength_mm : 1.0, i < 3 ? "mm" : "");

    const ba::LeiHsuCorrection fo = ba::lei_hsu_first_order(u, dv, tol);
    const ba::LeiHsuCorrection ex = ba::lei_hsu_exact(off, u, dv, tol);
    json out;
    // The correction of u = [x, y, z, θa, θc], split by unit (docs/cli.md: the unit in the key).
    out["du_mm"] = {fo.du[0], fo.du[1], fo.du[2]};
    out["du_rad"] = {fo.du[3], fo.du[4]};
    out["exact_du_mm"] = {ex.du[0], ex.du[1], ex.du[2]};
    out["exact_du_rad"] = {ex.du[3], ex.du[4]};
    out["singular"] = fo.singular;
    out["method"] = fo.singular
                        ? "first order: theta_a = 0 forms of seed-math (no C correction); exact: Gauss-Newton, C held"
                        : "first order: inverse Jacobian, orientation by least squares over (i,j,k); exact: "
                          "Gauss-Newton on F(u+du) = F(u) + dv";
    out["exact_converged"] = ex.converged;
    out["exact_iterations"] = ex.iterations;
    return out;
}

}  // namespace

std::string solve(SolveService service, std::string_view request) {
    json req;
    try {
        req = json::parse(request);
    } catch (const json::exception& e) {  // parse_error, and out_of_range for a number past double
        throw SolveError(std::string("malformed JSON: ") + e.what(), "");
    }
    if (!req.is_object()) throw SolveError("the request must be a JSON object", "");
    json answer;
    try {
        switch (service) {
            case SolveService::ssm:
                answer = solve_ssm(req);
                break;
            case SolveService::orientation:
                answer = solve_orientation(req);
                break;
            case SolveService::compensate:
                answer = solve_compensate(req);
                break;
        }
    } catch (const ba::AnalysisError& e) {  // what a solver refuses past the request's checks
        throw SolveError(e.what(), "");
    }
    return answer.dump();
}

}  // namespace ballbar::workflow
