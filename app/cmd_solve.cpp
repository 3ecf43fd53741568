// SPDX-License-Identifier: MIT
// `ballbar solve ssm|orientation|compensate`: the numerical services as a scriptable command
// (workflow/solve.hpp). One JSON request in (stdin or --input FILE), one JSON answer out (stdout). A
// refused request gets {"error": ..., "field": ...} on stderr and exit code 2. docs/analysis.md and
// docs/compensation.md document every shape.
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "ballbar/fileio/input.hpp"
#include "ballbar/workflow/solve.hpp"
#include "command.hpp"
#include "files.hpp"

namespace ballbar::app {
namespace {

using nlohmann::json;
using workflow::SolveError;
using workflow::SolveService;

/// The request: at most fileio::kMaxJsonBytes from a regular file or standard input.
std::string read_request(const std::string& input_path) {
    try {
        fileio::InputFile in = input_path.empty() || input_path == "-"
                                   ? fileio::InputFile::standard_input("request")
                                   : fileio::InputFile::open(input_path, "request file");
        std::string text = fileio::read_whole(in, fileio::kMaxJsonBytes);
        fileio::check_json_nesting(text, "request");
        return text;
    } catch (const fileio::FileError& e) {
        throw SolveError(e.what(), "--input");
    }
}

/// Runs one service on the request; prints the answer or the JSON error. Returns the exit code.
int run_solver(const std::string& input_path, SolveService service) {
    try {
        std::cout << workflow::solve(service, read_request(input_path)) << '\n';
        return kExitOk;
    } catch (const SolveError& e) {
        json err;
        err["error"] = readable_message(e.what());
        if (!e.field().empty()) err["field"] = e.field();
        // The message may quote the input's bytes (a parse error's "last read"): not UTF-8 is replaced,
        // not thrown (found by fuzz_cli_json).
        std::cerr << err.dump(-1, ' ', false, json::error_handler_t::replace) << '\n';
        return kExitUsage;
    }
}

void add_solver(CLI::App& solve, Globals& globals, const char* name, const char* description, const char* footer,
                SolveService service) {
    auto input = std::make_shared<std::string>();
    auto* sub = solve.add_subcommand(name, description);
    sub->add_option("--input", *input, "read the JSON request from FILE instead of stdin")->option_text("FILE");
    sub->footer(footer);
    sub->callback(
        [&globals, input, service]() { globals.action = [input, service]() { return run_solver(*input, service); }; });
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
               "Answer:   {\"linear_mm\":[...], \"exact_mm\":[...], \"condition_number\":c, \"exact_mm_std\":[...],\n"
               "           \"residual_rms_mm\":r|null, \"reading_sd_mm\":s, \"iterations\":k}\n"
               "delta_l_mm = measured minus nominal length; nominal = |point - socket| unless nominal_mm is given.\n"
               "Errors: {\"error\":..., \"field\":...} on stderr, exit code 2. See docs/analysis.md.",
               SolveService::ssm);
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
        SolveService::orientation);
    add_solver(*solve, globals, "compensate", "Lei & Hsu X'Y'ZA'C' correction du for a pose error dv (JSON)",
               "Request: {\"kinematics\":\"lei-hsu\", \"offsets_mm\":{\"Xw0\":..,\"Yw0\":..,\"Zw0\":..,\"Z3\":..},\n"
               "          \"u\":[x_m,y_m,z_m,theta_a_rad,theta_c_rad], \"dv\":[dx,dy,dz,di,dj,dk]}\n"
               "Answer:  {\"du_mm\":[...], \"du_rad\":[...], \"exact_du_mm\":[...], \"exact_du_rad\":[...],\n"
               "          \"singular\":false, \"method\":\"...\"}\n"
               "dv = ideal - actual pose (workpiece coordinates); du is added to the commanded axes.\n"
               "Errors: {\"error\":..., \"field\":...} on stderr, exit code 2. See docs/compensation.md.",
               SolveService::compensate);
}
