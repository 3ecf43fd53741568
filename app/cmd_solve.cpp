// SPDX-License-Identifier: MIT
// `ballbar solve`: the numerical services as a scriptable command. One JSON request in (stdin or
// --input FILE), one JSON answer out (stdout). A malformed request gets {"error": ..., "field": ...}
// on stderr and exit code 2. docs/analysis.md documents every shape.
//
// Other files may add further `solve` subcommands: root.get_subcommand("solve")->add_subcommand(...).
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <iostream>
#include <iterator>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "ballbar/analysis/limits.hpp"
#include "ballbar/analysis/orientation.hpp"
#include "ballbar/analysis/ssm.hpp"
#include "ballbar/fileio/input.hpp"
#include "command.hpp"
#include "files.hpp"

namespace ballbar::app {
namespace {

namespace ba = ballbar::analysis;
using nlohmann::json;

/// A request the solver cannot take: the message and the field (a JSON path such as "points_mm[2]").
struct RequestError {
    std::string message;
    std::string field;
};

std::string join(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
}
std::string index(const std::string& path, std::size_t i) {
    return path + "[" + std::to_string(i) + "]";
}

/// Read helpers: each names the field it complains about.
void only_keys(const json& obj, const std::string& path, std::initializer_list<const char*> allowed) {
    if (!obj.is_object()) throw RequestError{"must be a JSON object", path};
    for (const auto& item : obj.items()) {
        bool ok = false;
        for (const char* k : allowed) ok = ok || item.key() == k;
        if (!ok) throw RequestError{"unknown field", join(path, item.key())};
    }
}
const json* find(const json& obj, const std::string& path, const char* key, bool required) {
    const auto it = obj.find(key);
    if (it == obj.end() || it->is_null()) {
        if (required) throw RequestError{"missing", join(path, key)};
        return nullptr;
    }
    return &*it;
}
double number(const json& j, const std::string& field) {
    if (!j.is_number()) throw RequestError{"must be a number", field};
    const double v = j.get<double>();
    if (!std::isfinite(v)) throw RequestError{"must be finite", field};
    return v;
}
std::vector<double> numbers(const json& j, const std::string& field) {
    if (!j.is_array()) throw RequestError{"must be an array of numbers", field};
    std::vector<double> out;
    for (std::size_t i = 0; i < j.size(); ++i) out.push_back(number(j[i], index(field, i)));
    return out;
}
ba::Vec3 vec3(const json& j, const std::string& field) {
    if (!j.is_array() || j.size() != 3) throw RequestError{"must be an array of 3 numbers [x, y, z]", field};
    return {number(j[0], index(field, 0)), number(j[1], index(field, 1)), number(j[2], index(field, 2))};
}
double get_number(const json& obj, const std::string& path, const char* key) {
    return number(*find(obj, path, key, true), join(path, key));
}
ba::Vec3 get_vec3(const json& obj, const std::string& path, const char* key) {
    return vec3(*find(obj, path, key, true), join(path, key));
}
/// The documented range of a request's value (docs/analysis.md, "Ranges"), or RequestError naming it.
double within_range(double v, const std::string& field, double lo, double hi, const char* unit) {
    if (const std::string why = ba::limits::check_in(v, lo, hi, unit); !why.empty()) throw RequestError{why, field};
    return v;
}
ba::Vec3 within_range(const ba::Vec3& v, const std::string& field, double lim, const char* unit) {
    for (int i = 0; i < 3; ++i) within_range(v[i], index(field, static_cast<std::size_t>(i)), -lim, lim, unit);
    return v;
}
/// A position (socket, pivot, point) and a small length error (ΔV, Δl): ±100 m and ±10 mm.
ba::Vec3 get_position(const json& obj, const std::string& path, const char* key) {
    return within_range(get_vec3(obj, path, key), join(path, key), ba::limits::kPosition_mm, "mm");
}
ba::Vec3 get_error(const json& obj, const std::string& path, const char* key) {
    return within_range(get_vec3(obj, path, key), join(path, key), ba::limits::kSmallLength_mm, "mm");
}
/// A test's rotation, rad: at most one turn each way.
double get_rotation(const json& obj, const std::string& path, const char* key) {
    const double lim = ba::deg_to_rad(ba::limits::kRotation_deg);
    return within_range(get_number(obj, path, key), join(path, key), -lim, lim, "rad");
}
/// [0, 0, z] fields of the seed's models: x and y must be zero.
double get_axial(const json& obj, const std::string& path, const char* key, const char* why) {
    const ba::Vec3 v = get_position(obj, path, key);
    for (int i = 0; i < 2; ++i)
        if (v[i] != 0.0)
            throw RequestError{std::string("must be 0: ") + why, index(join(path, key), static_cast<std::size_t>(i))};
    return v.z();
}
json vec_json(const ba::Vec3& v) {
    return json::array({v.x(), v.y(), v.z()});
}

json read_request(const std::string& input_path) {
    std::string text;
    try {  // at most fileio::kMaxJsonBytes, from a regular file or standard input
        fileio::InputFile in = input_path.empty() || input_path == "-"
                                   ? fileio::InputFile::standard_input("request")
                                   : fileio::InputFile::open(input_path, "request file");
        text = fileio::read_whole(in, fileio::kMaxJsonBytes);
        fileio::check_json_nesting(text, "request");
    } catch (const fileio::FileError& e) {
        throw RequestError{e.what(), "--input"};
    }
    try {
        return json::parse(text);
    } catch (const json::exception& e) {  // parse_error, and out_of_range for a number past double
        throw RequestError{std::string("malformed JSON: ") + e.what(), ""};
    }
}

// ---- solve ssm

json solve_ssm(const json& req) {
    only_keys(req, "", {"socket_mm", "points_mm", "delta_l_mm", "std_mm", "nominal_mm", "max_condition"});
    const ba::Vec3 socket = get_position(req, "", "socket_mm");
    const json& jp = *find(req, "", "points_mm", true);
    if (!jp.is_array()) throw RequestError{"must be an array of [x, y, z] points", "points_mm"};
    std::vector<ba::Vec3> points;
    for (std::size_t i = 0; i < jp.size(); ++i) {
        points.push_back(
            within_range(vec3(jp[i], index("points_mm", i)), index("points_mm", i), ba::limits::kPosition_mm, "mm"));
        if ((points.back() - socket).norm() < 1e-6)
            throw RequestError{"coincides with the socket", index("points_mm", i)};
    }
    if (points.size() < 3)
        throw RequestError{"SSM needs at least 3 points, got " + std::to_string(points.size()), "points_mm"};
    const std::vector<double> dl = numbers(*find(req, "", "delta_l_mm", true), "delta_l_mm");
    for (std::size_t i = 0; i < dl.size(); ++i)
        within_range(dl[i], index("delta_l_mm", i), -ba::limits::kSmallLength_mm, ba::limits::kSmallLength_mm, "mm");
    if (dl.size() != points.size())
        throw RequestError{
            "has " + std::to_string(dl.size()) + " entries for " + std::to_string(points.size()) + " points",
            "delta_l_mm"};
    std::vector<double> nominal;
    if (const json* jn = find(req, "", "nominal_mm", false)) {
        nominal = numbers(*jn, "nominal_mm");
        if (nominal.size() != points.size())
            throw RequestError{
                "has " + std::to_string(nominal.size()) + " entries for " + std::to_string(points.size()) + " points",
                "nominal_mm"};
        for (std::size_t i = 0; i < nominal.size(); ++i)
            if (const std::string why = ba::limits::check_above(nominal[i], 0, ba::limits::kLength_mm, "mm");
                !why.empty())
                throw RequestError{why, index("nominal_mm", i)};
    }
    ba::SsmOptions opt;
    if (const json* js = find(req, "", "std_mm", false)) {
        opt.reading_std_mm = number(*js, "std_mm");
        within_range(opt.reading_std_mm, "std_mm", 0, ba::limits::kSmallLength_mm, "mm");
    }
    if (const json* jc = find(req, "", "max_condition", false)) {
        opt.max_condition = number(*jc, "max_condition");
        within_range(opt.max_condition, "max_condition", 1, 1e12, "");
    }
    // The layout's conditioning is the points' fault; anything the solver refuses after that, the readings'.
    const double cond = ba::ssm_condition_number(socket, points);
    if (!(cond <= opt.max_condition)) {
        try {
            ba::solve_ssm(socket, points, dl, nominal, opt);
        } catch (const ba::AnalysisError& e) {
            throw RequestError{e.what(), "points_mm"};
        }
    }
    ba::SsmResult r;
    try {
        r = ba::solve_ssm(socket, points, dl, nominal, opt);
    } catch (const ba::AnalysisError& e) {
        throw RequestError{e.what(), "delta_l_mm"};
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

// ---- solve orientation

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

ba::OrientationSolution rtttr_spindle(const json& j, const std::string& p) {
    only_keys(j, p, {"pivot_mm", "tool_ball_mm", "beta_rad", "dV1_mm", "dV2_mm"});
    ba::RtttrSpindleInput in;
    in.pivot_mm = get_position(j, p, "pivot_mm");
    in.z_r_mm = get_axial(j, p, "tool_ball_mm", "the seed's model has the tool ball on the spindle axis");
    in.beta_rad = get_rotation(j, p, "beta_rad");
    in.dV1_mm = get_error(j, p, "dV1_mm");
    in.dV2_mm = get_error(j, p, "dV2_mm");
    return ba::solve_orientation(in);
}

ba::OrientationSolution rtttr_table(const json& j, const std::string& p) {
    only_keys(j, p, {"a_pivot_mm", "socket_mm", "alpha_rad", "dV1_mm", "dV2_mm"});
    ba::RtttrTableInput in;
    in.a_pivot_mm = get_position(j, p, "a_pivot_mm");
    in.socket_mm = get_position(j, p, "socket_mm");
    in.alpha_rad = get_rotation(j, p, "alpha_rad");
    in.dV1_mm = get_error(j, p, "dV1_mm");
    in.dV2_mm = get_error(j, p, "dV2_mm");
    return ba::solve_orientation(in);
}

json solve_rtttr(const json& req) {
    only_keys(req, "", {"machine", "spindle", "table"});
    const json* js = find(req, "", "spindle", false);
    const json* jt = find(req, "", "table", false);
    if (!js && !jt) throw RequestError{"give a spindle part, a table part, or both", "spindle"};
    std::optional<ba::OrientationSolution> s, t;
    if (js) s = rtttr_spindle(*js, "spindle");
    if (jt) t = rtttr_table(*jt, "table");
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

json solve_orientation(const json& req) {
    if (!req.is_object()) throw RequestError{"must be a JSON object", ""};
    const json& jm = *find(req, "", "machine", true);
    const auto type = jm.is_string() ? ba::parse_machine_type(jm.get<std::string>()) : std::nullopt;
    if (!type) throw RequestError{"must be \"RRTTT\", \"TTTRR\" or \"RTTTR\"", "machine"};
    switch (*type) {
        case ba::MachineType::RRTTT: {
            only_keys(req, "", {"machine", "pivot_mm", "tool_ball_mm", "alpha_rad", "beta_rad", "dV1_mm", "dV2_mm"});
            ba::RrtttInput in;
            in.pivot_mm = get_position(req, "", "pivot_mm");
            in.z_r_mm = get_axial(req, "", "tool_ball_mm", "the seed's model has the tool ball on the spindle axis");
            in.alpha_rad = get_rotation(req, "", "alpha_rad");
            in.beta_rad = get_rotation(req, "", "beta_rad");
            in.dV1_mm = get_error(req, "", "dV1_mm");
            in.dV2_mm = get_error(req, "", "dV2_mm");
            return solution_json(ba::solve_orientation(in), {true, true, false});
        }
        case ba::MachineType::TTTRR: {
            only_keys(
                req, "",
                {"machine", "a_pivot_mm", "c_offset_mm", "socket_mm", "alpha_rad", "gamma_rad", "dV1_mm", "dV2_mm"});
            ba::TtttrrInput in;
            in.a_pivot_mm = get_position(req, "", "a_pivot_mm");
            in.z_ag_mm = get_axial(req, "", "c_offset_mm", "the seed's model has the C axis meet the A axis");
            in.socket_mm = get_position(req, "", "socket_mm");
            in.alpha_rad = get_rotation(req, "", "alpha_rad");
            in.gamma_rad = get_rotation(req, "", "gamma_rad");
            in.dV1_mm = get_error(req, "", "dV1_mm");
            in.dV2_mm = get_error(req, "", "dV2_mm");
            return solution_json(ba::solve_orientation(in), {true, false, true});
        }
        case ba::MachineType::RTTTR:
            return solve_rtttr(req);
    }
    throw RequestError{"unsupported machine type", "machine"};
}

/// Runs one solver on the request; prints the answer or the JSON error. Returns the exit code.
int run_solver(const std::string& input_path, json (*solver)(const json&)) {
    try {
        const json answer = solver(read_request(input_path));
        std::cout << answer.dump() << '\n';
        return kExitOk;
    } catch (const RequestError& e) {
        json err;
        err["error"] = readable_message(e.message);
        if (!e.field.empty()) err["field"] = e.field;
        // The message may quote the input's bytes (a parse error's "last read"): not UTF-8 is replaced,
        // not thrown (found by fuzz_cli_json).
        std::cerr << err.dump(-1, ' ', false, json::error_handler_t::replace) << '\n';
        return kExitUsage;
    } catch (const ba::AnalysisError& e) {
        std::cerr << json{{"error", e.what()}}.dump(-1, ' ', false, json::error_handler_t::replace) << '\n';
        return kExitUsage;
    }
}

void add_solver(CLI::App& solve, Globals& globals, const char* name, const char* description, const char* footer,
                json (*solver)(const json&)) {
    auto input = std::make_shared<std::string>();
    auto* sub = solve.add_subcommand(name, description);
    sub->add_option("--input", *input, "read the JSON request from FILE instead of stdin")->option_text("FILE");
    sub->footer(footer);
    sub->callback(
        [&globals, input, solver]() { globals.action = [input, solver]() { return run_solver(*input, solver); }; });
}

}  // namespace
}  // namespace ballbar::app

BALLBAR_COMMAND(solve) {
    using namespace ballbar::app;
    auto* solve =
        root.add_subcommand("solve", "Numerical services as JSON: one request in (stdin or --input), one answer out");
    solve->require_subcommand(1);
    add_solver(*solve, globals, "ssm", "Total position error of one location from n >= 3 bar readings (SSM)",
               "Request:  {\"socket_mm\":[x,y,z], \"points_mm\":[[x,y,z],...], \"delta_l_mm\":[...],\n"
               "           \"std_mm\":0.0005, \"nominal_mm\":[...], \"max_condition\":30}  (last three optional)\n"
               "Answer:   {\"linear_mm\":[...], \"exact_mm\":[...], \"condition_number\":c, \"std_mm\":[...],\n"
               "           \"residual_rms_mm\":r|null, \"reading_std_mm\":s, \"iterations\":k}\n"
               "delta_l_mm = measured minus nominal length; nominal = |point - socket| unless nominal_mm is given.\n"
               "Errors: {\"error\":..., \"field\":...} on stderr, exit code 2. See docs/analysis.md.",
               &solve_ssm);
    add_solver(
        *solve, globals, "orientation",
        "Orientation errors of the rotary axes: corrected first-order formulas and exact inversion",
        "RRTTT:  {\"machine\":\"RRTTT\", \"pivot_mm\":[...], \"tool_ball_mm\":[0,0,zr], \"alpha_rad\":a,\n"
        "         \"beta_rad\":b, \"dV1_mm\":[...], \"dV2_mm\":[...]}\n"
        "TTTRR:  {\"machine\":\"TTTRR\", \"a_pivot_mm\":[...], \"c_offset_mm\":[0,0,zag], \"socket_mm\":[...],\n"
        "         \"alpha_rad\":a, \"gamma_rad\":g, \"dV1_mm\":[...], \"dV2_mm\":[...]}\n"
        "RTTTR:  {\"machine\":\"RTTTR\", \"spindle\":{\"pivot_mm\", \"tool_ball_mm\", \"beta_rad\", \"dV1_mm\",\n"
        "         \"dV2_mm\"}, \"table\":{\"a_pivot_mm\", \"socket_mm\", \"alpha_rad\", \"dV1_mm\", \"dV2_mm\"}}\n"
        "Answer: {\"first_order\":{\"d_alpha_rad\",...}|null, \"exact\":{...}|null, \"nominal_after_mm\":[...],\n"
        "         \"singular\":\"<why>\" (when something is null)}. Lengths mm, angles rad. docs/analysis.md.",
        &solve_orientation);
}
