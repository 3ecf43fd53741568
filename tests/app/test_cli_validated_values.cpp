// SPDX-License-Identifier: MIT
// Issue 15, validated values: for every input the CLI reads (readings files, machine and plan files,
// circle plan options, traces, models, offsets tables, emulator configurations and faults, `solve`
// requests), a value out of its documented range, not finite, or under an unknown key is refused
// with exit 2 and a message naming the field; and no NC word outside the controller's format is ever
// written.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "cli_harness.hpp"

namespace ballbar::test {
namespace {

struct Refusal {
    const char* name;
    std::vector<std::pair<std::string, std::string>> files;  ///< written into the run's directory
    std::string args;                                        ///< {dir} is the directory
    std::string says;                                        ///< in stderr
    std::string input = {};                                  ///< stdin
};

void PrintTo(const Refusal& r, std::ostream* os) {
    *os << r.name;
}

const std::string kReadingsHead =
    "# ballbar-readings/1\n"
    "# machine: {\"type\":\"TTTRR\",\"a_pivot_mm\":[0,0,0],\"c_offset_mm\":[0,0,-100],\"tool_ball_mm\":[0,0,0]}\n"
    "X_mm,Y_mm,Z_mm,A_deg,C_deg,socket_x_mm,socket_y_mm,socket_z_mm,measured_mm\n"
    "32.375,-14.312,-120.042,0,0,-49.275,-14.312,-77.777,100.0021\n";
const std::string kMachine =
    R"({"format":"ballbar-machine/1","type":"TTTRR","a_pivot_mm":[0,0,0],"c_offset_mm":[0,0,-100],)"
    R"("tool_ball_mm":[0,0,0],"dialect":"fanuc","feed_mm_min":2000)";
const std::string kPlanTests =
    R"({"format":"ballbar-plan/1","tests":[{"socket_mm":[-49.275,-14.312,-77.777],"rotation_deg":{"A":10,"C":30}}])";
const std::string kModelMachine =
    R"("machine":{"type":"TTTRR","a_pivot_mm":[0,0,0],"c_offset_mm":[0,0,-100],"tool_ball_mm":[0,0,0]})";
const std::string kModel = R"({"format":"ballbar-model/1",)" + kModelMachine + R"(,"params":{"X0C":0.01}})";
const std::string kProgramValidatedValues = "%\nO0001\nG90 G21\nG0 X0 Y0 Z0 A0 C0\nG1 X10 F1000\nM30\n%\n";
const std::string kTestHeader =
    R"(# test: {"kind": "circular", "plane": "XY", "radius_mm": 100.0, "centre_mm": [0, 0, 0], )"
    R"("feed_mm_min": 1000.0, "feed_in_mm": 1.5, "runs": [{"direction": "ccw", "start_deg": 0, )"
    R"("overshoot_deg": 45, "data_arc_deg": 360}]})";
const std::string kCompensate = "compensate --model m.json --program p.nc --out {dir}/out.nc";

std::string expand_validated_values(std::string args, const std::string& dir) {
    for (std::size_t at; (at = args.find("{dir}")) != std::string::npos;) args.replace(at, 5, dir);
    return args;
}

class RefusedInput : public ::testing::TestWithParam<Refusal> {};

TEST_P(RefusedInput, ExitsTwoNamingTheField) {
    const Refusal& c = GetParam();
    TempDir dir;
    for (const auto& [name, text] : c.files) std::ofstream(dir.path / name, std::ios::binary) << text;
    std::string args = c.args;  // the files by their full path
    for (const auto& [name, text] : c.files) {
        for (std::size_t at = 0; (at = args.find(" " + name, at)) != std::string::npos; at += name.size() + 1) {
            args.replace(at + 1, name.size(), dir.file(name));
        }
    }
    const CliRun r = run(dir, expand_validated_values(args, dir.path.string()), c.input);
    EXPECT_EQ(r.code, 2) << r.err << r.out;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir.file("out.nc"))) << "nothing is written";
    EXPECT_EQ(r.out.find("G4 P"), std::string::npos) << "no program on stdout: " << r.out;
}

INSTANTIATE_TEST_SUITE_P(
    Inputs, RefusedInput,
    ::testing::Values(
        // readings files (ballbar import)
        Refusal{"import_X_1e308",
                {{"r.csv", kReadingsHead + "1e308,-14.312,-120.042,0,0,-49.275,-14.312,-77.777,100.0021\n"}},
                "import r.csv",
                "line 5: column \"X_mm\" = 1e+308 is outside [-100000, 100000] mm"},
        Refusal{"import_A_deg_1e308",
                {{"r.csv", kReadingsHead + "32.375,-14.312,-120.042,1e308,0,-49.275,-14.312,-77.777,100.0021\n"}},
                "import r.csv",
                "line 5: column \"A_deg\" = 1e+308 is outside"},
        Refusal{"import_measured_1e308",
                {{"r.csv", kReadingsHead + "32.375,-14.312,-120.042,0,0,-49.275,-14.312,-77.777,1e308\n"}},
                "import r.csv",
                "column \"measured_mm\" = 1e+308 must be > 0"},
        // machine files (measure --dry-run)
        Refusal{"machine_unknown_key",
                {{"m.json", kMachine + R"(,"feed_mm_mn":1500})"}},
                "measure --dry-run --machine m.json",
                "machine file: unknown key \"feed_mm_mn\""},
        Refusal{"machine_feed_1e_minus_300",
                {{"m.json", kMachine + R"(,"feed_mm_min":1e-300})"}},
                "measure --dry-run --machine m.json",
                "feed_mm_min = 1e-300 is outside [0.1, 200000] mm/min"},
        Refusal{"machine_feed_1e308",
                {{"m.json", kMachine + R"(,"feed_mm_min":1e308})"}},
                "measure --dry-run --machine m.json",
                "feed_mm_min = 1e+308 is outside"},
        Refusal{"machine_travel_1e308",
                {{"m.json", kMachine + R"(,"travel":{"X_mm":[-1e308,1e308]}})"}},
                "measure --dry-run --machine m.json",
                "travel.X_mm[0] = -1e+308 is outside"},
        // plan files (measure --dry-run --plan)
        Refusal{"plan_dwell_1e308",
                {{"m.json", kMachine + "}"}, {"p.json", kPlanTests + R"(,"dwell_s":1e308})"}},
                "measure --dry-run --machine m.json --plan p.json",
                "plan file: dwell_s = 1e+308 s"},
        Refusal{"plan_dwell_shorter_than_two_windows",
                {{"m.json", kMachine + "}"}, {"p.json", kPlanTests + R"(,"dwell_s":0.8,"capture":{"window_s":0.5}})"}},
                "measure --dry-run --machine m.json --plan p.json",
                "dwell_s = 0.8 s: it must be at least two capture windows"},
        Refusal{"plan_negative_retries",
                {{"m.json", kMachine + "}"}, {"p.json", kPlanTests + R"(,"capture":{"retries":-1}})"}},
                "measure --dry-run --machine m.json --plan p.json",
                "capture: retries = -1 is not an integer"},
        Refusal{"plan_zero_tolerance",
                {{"m.json", kMachine + "}"}, {"p.json", kPlanTests + R"(,"capture":{"tolerance_mm":0}})"}},
                "measure --dry-run --machine m.json --plan p.json",
                "capture: tolerance_mm = 0 must be > 0"},
        Refusal{"plan_unknown_key",
                {{"m.json", kMachine + "}"}, {"p.json", kPlanTests + R"(,"dwel_s":2})"}},
                "measure --dry-run --machine m.json --plan p.json",
                "plan file: unknown key \"dwel_s\""},
        Refusal{"measure_plan_negative_retries",
                {{"m.json", kMachine + "}"}, {"p.json", kPlanTests + R"(,"capture":{"retries":-1}})"}},
                "measure --device serial:/dev/null --machine m.json --plan p.json --non-interactive",
                "capture: retries = -1"},
        // circle plan options
        Refusal{"circle_feed_1e_minus_300",
                {},
                "circle plan --feed 1e-300",
                "--feed: 1e-300 is outside [0.1, 200000] mm/min"},
        Refusal{"circle_feed_1e308", {}, "circle plan --feed 1e308", "--feed: 1e308 is outside"},
        Refusal{"circle_dwell_1e308", {}, "circle plan --dwell 1e308", "--dwell: 1e308 is outside [0, 3600] s"},
        Refusal{"circle_dwell_1e308_linuxcnc", {}, "circle plan --dialect linuxcnc --dwell 1e308", "--dwell: 1e308"},
        Refusal{"circle_start_1e308", {}, "circle plan --start 1e308", "--start: 1e308 is outside [-36000, 36000]"},
        Refusal{"circle_negative_overshoot", {}, "circle plan --overshoot -5", "--overshoot: -5 is outside [0, 360]"},
        Refusal{"circle_radius_1e308", {}, "circle plan --radius 1e308", "--radius: 1e308 is outside (0, 10000] mm"},
        // issue 24: every numeric option has a range; nan and inf are no numbers of any range
        Refusal{"circle_radius_nan", {}, "circle plan --radius nan", "--radius: nan is not a finite number"},
        Refusal{"circle_centre_inf", {}, "circle plan --centre inf 0 0", "--centre: inf is not a finite number"},
        Refusal{"circle_arc_20", {}, "circle plan --arc 20", "--arc: 20 is outside [30, 360]"},
        Refusal{"circle_rate_0", {}, "circle plan --rate 0", "--rate: 0 is outside [1, 100000] readings/s"},
        Refusal{"circle_feed_in_nan", {}, "circle plan --feed-in nan", "--feed-in: nan is not a finite number"},
        Refusal{
            "analyze_tolerance_inf", {}, "circle analyze x.csv --tolerance inf", "--tolerance: inf is not a finite"},
        Refusal{"report_tolerance_negative", {}, "report 1 --tolerance -3", "--tolerance: -3 is outside (0, 10000]"},
        Refusal{"compensate_chord_1000",
                {{"m.json", kModel}, {"p.nc", kProgramValidatedValues}},
                kCompensate + " --chord-tolerance 1000",
                "--chord-tolerance: 1000 is outside [1e-05, 0.1] mm"},
        Refusal{"compensate_chord_inf",
                {{"m.json", kModel}, {"p.nc", kProgramValidatedValues}},
                kCompensate + " --chord-tolerance inf",
                "--chord-tolerance: inf is not a finite number"},
        Refusal{"compensate_chord_1e308",
                {{"m.json", kModel}, {"p.nc", kProgramValidatedValues}},
                kCompensate + " --chord-tolerance 1e308",
                "--chord-tolerance: 1e308 is outside"},
        Refusal{"compensate_singular_nan",
                {{"m.json", kModel}, {"p.nc", kProgramValidatedValues}},
                kCompensate + " --singular-deg nan",
                "--singular-deg: nan is not a finite number"},
        Refusal{"discover_noise_nan", {}, "discover x.csv --noise-um nan", "--noise-um: nan is not a finite number"},
        Refusal{
            "monitor_seconds_inf", {}, "monitor --device emulator: --seconds inf", "--seconds: inf is not a finite"},
        Refusal{"emulate_watchdog_nan", {}, "emulate --pty --watchdog nan", "--watchdog: nan is not a finite number"},
        Refusal{"emulate_tcp_port_70000", {}, "emulate --tcp 70000", "--tcp: 70000 is outside [0, 65535]"},
        Refusal{"measure_from_point_negative", {}, "measure --dry-run --from-point -1", "--from-point: -1 is outside"},
        Refusal{"circle_centre_beyond_the_X_word",
                {},
                "circle plan --centre 99990 0 0",
                "NC word X: 100091.5 does not fit the controller's word format"},
        // traces (circle analyze)
        Refusal{"trace_time_1e308",
                {{"t.csv", "# ballbar-trace/1\n" + kTestHeader + "\ntime_s,measured_mm\n0,101.5\n1e308,101.5\n"}},
                "circle analyze t.csv",
                "line 5: time_s = 1e+308 is outside"},
        Refusal{"trace_unknown_test_key",
                {{"t.csv", "# ballbar-trace/1\n" + kTestHeader.substr(0, kTestHeader.size() - 1) +
                               ", \"units\": \"mm\"}" + "\ntime_s,measured_mm\n0,101.5\n"}},
                "circle analyze t.csv",
                "unknown key \"units\""},
        // models and offsets tables (compensate)
        Refusal{"model_param_1e308",
                {{"m.json", R"({"format":"ballbar-model/1",)" + kModelMachine + R"(,"params":{"X0C":1e308}})"},
                 {"p.nc", kProgramValidatedValues}},
                kCompensate,
                "params.X0C = 1e+308 is outside [-1000, 1000] mm"},
        Refusal{"model_unknown_key",
                {{"m.json", R"({"format":"ballbar-model/1",)" + kModelMachine + R"(,"params":{},"parms":{}})"},
                 {"p.nc", kProgramValidatedValues}},
                kCompensate,
                "parms: unknown key"},
        Refusal{"model_machine_1e308",
                {{"m.json", R"({"machine":{"type":"TTTRR","a_pivot_mm":[0,0,0],"c_offset_mm":[0,0,1e308],)"
                            R"("tool_ball_mm":[0,0,0]},"params":{}})"},
                 {"p.nc", kProgramValidatedValues}},
                kCompensate,
                "machine.c_offset_mm[2] = 1e+308"},
        Refusal{"offsets_1e308",
                {{"m.json", kModel},
                 {"p.nc", kProgramValidatedValues},
                 {"o.json", R"({"work_offsets":{"G54":{"X_mm":1e308}}})"}},
                kCompensate + " --offsets o.json",
                "work_offsets.G54.X_mm = 1e+308 is outside"},
        Refusal{"offsets_rotary_1e308",
                {{"m.json", kModel},
                 {"p.nc", kProgramValidatedValues},
                 {"o.json", R"({"work_offsets":{"G54":{"C_deg":1e308}}})"}},
                kCompensate + " --offsets o.json",
                "work_offsets.G54.C_deg = 1e+308 is outside [-36000, 36000] deg"},
        Refusal{"compensated_word_beyond_the_format",
                {{"m.json", kModel}, {"p.nc", "%\nO0001\nG90 G21\nG0 X0 Y0 Z0 A0 C0\nG1 X150000 F1000\nM30\n%\n"}},
                kCompensate,
                "line 5: NC word X: "},
        // emulator configuration and faults
        Refusal{"emulator_config_noise_1e308",
                {{"c.json", R"({"instrument":{"noise_um":1e308}})"}},
                "emulate --pty --config c.json",
                "emulator config: instrument.noise_um = 1e+308 is outside"},
        Refusal{"emulator_config_errors_1e308",
                {{"c.json", R"({"machine":{"errors":{"X0C_um":1e308}}})"}},
                "emulate --pty --config c.json",
                "machine.errors.X0C_um: X0C = 1e+305 is outside"},
        Refusal{"demo_faults_reply_delay_1e308",
                {},
                "demo --faults '{\"reply_delay_ms\":1e308}'",
                "faults.reply_delay_ms = 1e+308 is outside"},
        Refusal{"gauge_faults_nan",
                {},
                "emulate --pty --instrument sylvac --faults not-ready=nan",
                "a probability must be 0..1"},
        // solve requests: {"error", "field"} on stderr
        Refusal{"solve_ssm_point_1e308",
                {},
                "solve ssm",
                R"("field":"points_mm[1][0]")",
                R"({"socket_mm":[0,0,0],"points_mm":[[100,0,0],[1e308,0,0],[0,0,100]],"delta_l_mm":[0,0,0]})"},
        Refusal{"solve_ssm_delta_l_1e3",
                {},
                "solve ssm",
                R"("field":"delta_l_mm[2]")",
                R"({"socket_mm":[0,0,0],"points_mm":[[100,0,0],[0,100,0],[0,0,100]],"delta_l_mm":[0,0,1000]})"},
        Refusal{"solve_orientation_alpha_1e3",
                {},
                "solve orientation",
                R"("field":"alpha_rad")",
                R"({"machine":"RRTTT","pivot_mm":[0,0,0],"tool_ball_mm":[0,0,-100],"alpha_rad":1000,)"
                R"("beta_rad":0,"dV1_mm":[0,0,0],"dV2_mm":[0,0,0]})"},
        Refusal{"solve_orientation_dV_1e308",
                {},
                "solve orientation",
                R"("field":"dV2_mm[0]")",
                R"({"machine":"RRTTT","pivot_mm":[0,0,0],"tool_ball_mm":[0,0,-100],"alpha_rad":0.5,)"
                R"("beta_rad":0,"dV1_mm":[0,0,0],"dV2_mm":[1e308,0,0]})"},
        Refusal{"solve_compensate_dv_1e5",
                {},
                "solve compensate",
                R"("field":"dv[0]")",
                R"({"kinematics":"lei-hsu","u":[0,0,0,0.1,0.2],"dv":[1e5,0,0,0,0,0]})"}),
    [](const auto& param_info) { return std::string(param_info.param.name); });

}  // namespace
}  // namespace ballbar::test
