// SPDX-License-Identifier: MIT
// `ballbar solve compensate`: the Lei & Hsu X'Y'ZA'C' correction as a JSON service (lei_hsu.hpp).
//   in:  {"kinematics":"lei-hsu", "offsets_mm":{"Xw0":…, "Yw0":…, "Zw0":…, "Z3":…},
//         "u":[x_m, y_m, z_m, theta_a_rad, theta_c_rad], "dv":[dx, dy, dz, di, dj, dk],
//         "singular_tolerance":sin(0.06°)}                 (offsets_mm and singular_tolerance optional)
//   out: {"du":[…], "exact_du":[…], "singular":false, "method":"…", "exact_iterations":k}
// dv = ideal − actual pose in workpiece coordinates (the paper's Eq. 16). A malformed request gets
// {"error": …, "field": …} on stderr and exit code 2.
#include <cmath>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "ballbar/analysis/compensate.hpp"
#include "ballbar/analysis/lei_hsu.hpp"
#include "ballbar/analysis/limits.hpp"
#include "ballbar/fileio/input.hpp"
#include "command.hpp"
#include "files.hpp"

namespace ballbar::app {
namespace {

namespace ba = ballbar::analysis;
using nlohmann::json;

struct BadField {
    std::string message;
    std::string field;
};

double finite_number(const json& j, const std::string& field) {
    if (!j.is_number()) throw BadField{"must be a number", field};
    const double v = j.get<double>();
    if (!std::isfinite(v)) throw BadField{"must be finite", field};
    return v;
}

/// `v` within [-lim, lim] (docs/compensation.md, "Ranges"), or BadField naming it.
double within(double v, double lim, const char* unit, const std::string& field) {
    if (const std::string why = ba::limits::check_in(v, -lim, lim, unit); !why.empty()) throw BadField{why, field};
    return v;
}

template <int N>
Eigen::Matrix<double, N, 1> fixed_array(const json& req, const char* key, const char* shape) {
    const auto it = req.find(key);
    if (it == req.end() || it->is_null()) throw BadField{"missing", key};
    if (!it->is_array() || it->size() != static_cast<std::size_t>(N))
        throw BadField{std::string("must be an array of ") + std::to_string(N) + " numbers " + shape, key};
    Eigen::Matrix<double, N, 1> v;
    for (int i = 0; i < N; ++i)
        v[i] = finite_number((*it)[static_cast<std::size_t>(i)], std::string(key) + "[" + std::to_string(i) + "]");
    return v;
}

json solve_compensate(const json& req) {
    if (!req.is_object()) throw BadField{"the request must be a JSON object", ""};
    for (const auto& item : req.items())
        if (item.key() != "kinematics" && item.key() != "offsets_mm" && item.key() != "u" && item.key() != "dv" &&
            item.key() != "singular_tolerance")
            throw BadField{"unknown field", item.key()};
    const auto kin = req.find("kinematics");
    if (kin == req.end()) throw BadField{"missing", "kinematics"};
    if (!kin->is_string() || kin->get<std::string>() != "lei-hsu")
        throw BadField{"must be \"lei-hsu\" (the X'Y'ZA'C' machine of Lei & Hsu)", "kinematics"};
    ba::LeiHsuOffsets off;
    if (const auto o = req.find("offsets_mm"); o != req.end() && !o->is_null()) {
        if (!o->is_object()) throw BadField{"must be an object {\"Xw0\", \"Yw0\", \"Zw0\", \"Z3\"}", "offsets_mm"};
        for (const auto& item : o->items()) {
            const std::string f = "offsets_mm." + item.key();
            if (item.value().is_number()) within(item.value().get<double>(), ba::limits::kPosition_mm, "mm", f);
            if (item.key() == "Xw0")
                off.Xw0_mm = finite_number(item.value(), f);
            else if (item.key() == "Yw0")
                off.Yw0_mm = finite_number(item.value(), f);
            else if (item.key() == "Zw0")
                off.Zw0_mm = finite_number(item.value(), f);
            else if (item.key() == "Z3")
                off.Z3_mm = finite_number(item.value(), f);
            else
                throw BadField{"unknown field", f};
        }
    }
    // The same default as `ballbar compensate --singular-deg` (0.06°): a tolerance of 1e-9 let dθc
    // grow to 1/sin(θa) ≈ 1e9 × the direction error near θa = 0.
    double tol = ba::default_singular_tolerance();
    if (const auto t = req.find("singular_tolerance"); t != req.end() && !t->is_null()) {
        tol = finite_number(*t, "singular_tolerance");
        if (tol < 0 || tol >= 1) throw BadField{"must be in [0, 1)", "singular_tolerance"};
    }
    const ba::Vec5 u = fixed_array<5>(req, "u", "[x_m, y_m, z_m, theta_a_rad, theta_c_rad]");
    const ba::Vec6 dv = fixed_array<6>(req, "dv", "[dx, dy, dz, di, dj, dk]");
    const double turns = ba::deg_to_rad(ba::limits::kRotary_deg);
    for (int i = 0; i < 5; ++i)
        within(u[i], i < 3 ? ba::limits::kPosition_mm : turns, i < 3 ? "mm" : "rad", "u[" + std::to_string(i) + "]");
    for (int i = 0; i < 6; ++i)  // a pose error: mm, and the change of a unit direction
        within(dv[i], i < 3 ? ba::limits::kSmallLength_mm : 1.0, i < 3 ? "mm" : "", "dv[" + std::to_string(i) + "]");

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

int run_solve_compensate(const std::string& input_path) {
    try {
        std::string text;
        try {  // at most fileio::kMaxJsonBytes, from a regular file or standard input
            fileio::InputFile in = input_path.empty() || input_path == "-"
                                       ? fileio::InputFile::standard_input("request")
                                       : fileio::InputFile::open(input_path, "request file");
            text = fileio::read_whole(in, fileio::kMaxJsonBytes);
            fileio::check_json_nesting(text, "request");
        } catch (const fileio::FileError& e) {
            throw BadField{e.what(), "--input"};
        }
        json req;
        try {
            req = json::parse(text);
        } catch (const json::exception& e) {  // parse_error, and out_of_range for a number past double
            throw BadField{std::string("malformed JSON: ") + e.what(), ""};
        }
        std::cout << solve_compensate(req).dump() << '\n';
        return kExitOk;
    } catch (const BadField& e) {
        json err;
        err["error"] = readable_message(e.message);
        if (!e.field.empty()) err["field"] = e.field;
        std::cerr << err.dump(-1, ' ', false, json::error_handler_t::replace) << '\n';  // input bytes quoted
        return kExitUsage;
    }
}

}  // namespace
}  // namespace ballbar::app

// Registered after `solve` (alphabetical order of the identifiers), which creates the parent command.
BALLBAR_COMMAND(solve_compensate) {
    using namespace ballbar::app;
    CLI::App* solve = nullptr;
    try {
        solve = root.get_subcommand("solve");
    } catch (const CLI::OptionNotFound&) {
        solve = root.add_subcommand("solve", "Numerical services as JSON");
        solve->require_subcommand(1);
    }
    auto input = std::make_shared<std::string>();
    auto* sub = solve->add_subcommand("compensate", "Lei & Hsu X'Y'ZA'C' correction du for a pose error dv (JSON)");
    sub->add_option("--input", *input, "read the JSON request from FILE instead of stdin")->option_text("FILE");
    sub->footer(
        "Request: {\"kinematics\":\"lei-hsu\", \"offsets_mm\":{\"Xw0\":..,\"Yw0\":..,\"Zw0\":..,\"Z3\":..},\n"
        "          \"u\":[x_m,y_m,z_m,theta_a_rad,theta_c_rad], \"dv\":[dx,dy,dz,di,dj,dk]}\n"
        "Answer:  {\"du\":[...], \"exact_du\":[...], \"singular\":false, \"method\":\"...\"}\n"
        "dv = ideal - actual pose (workpiece coordinates); du is added to the commanded axes.\n"
        "Errors: {\"error\":..., \"field\":...} on stderr, exit code 2. See docs/compensation.md.");
    sub->callback([&globals, input]() { globals.action = [input]() { return run_solve_compensate(*input); }; });
}
