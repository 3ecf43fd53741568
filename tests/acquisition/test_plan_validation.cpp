// SPDX-License-Identifier: MIT
// Machine and plan files: unknown keys refused, every number finite and within its documented range
// (docs/procedure.md), the message naming the field; and the NC program's words in the controller's
// format whatever the plan.
#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include "ballbar/acquisition/nc_writer.hpp"
#include "ballbar/acquisition/plan.hpp"

namespace ballbar::acquisition {
namespace {

using analysis::MachineType;

struct Case {
    const char* name;
    std::string text;  ///< the file, or the keys added to a valid one
    const char* says;  ///< what the message must contain (the field)
};

void PrintTo(const Case& c, std::ostream* os) {
    *os << c.name;
}

std::string refusal(const std::function<void()>& parse) {
    try {
        parse();
    } catch (const PlanError& e) {
        return e.what();
    }
    return "accepted";
}

// ---- machine files

const std::string kMachine = R"("format":"ballbar-machine/1","type":"TTTRR")";

class BadMachineFile : public ::testing::TestWithParam<Case> {};

TEST_P(BadMachineFile, IsRefusedNamingTheField) {
    const Case& c = GetParam();
    const std::string why = refusal([&] { parse_machine_file("{" + kMachine + "," + c.text + "}"); });
    EXPECT_EQ(why.rfind("machine file: ", 0), 0u) << why;
    EXPECT_NE(why.find(c.says), std::string::npos) << why;
}

INSTANTIATE_TEST_SUITE_P(
    Values, BadMachineFile,
    ::testing::Values(
        Case{"unknown_key", R"("feed_mm_mn":1500)", "unknown key \"feed_mm_mn\""},
        Case{"unknown_key_travle", R"("travle":{"X_mm":[0,1]})", "unknown key \"travle\""},
        Case{"feed_1e_minus_300", R"("feed_mm_min":1e-300)", "feed_mm_min = 1e-300 is outside"},
        Case{"feed_1e308", R"("feed_mm_min":1e308)", "feed_mm_min = 1e+308 is outside"},
        Case{"feed_zero", R"("feed_mm_min":0)", "feed_mm_min = 0 is outside"},
        Case{"travel_1e308", R"("travel":{"X_mm":[-1e308,1e308]})", "travel.X_mm[0] = -1e+308"},
        Case{"travel_rotary_1e308", R"("travel":{"C_deg":[0,1e308]})", "travel.C_deg[1] = 1e+308"},
        Case{"pivot_1e308", R"("a_pivot_mm":[1e308,0,0])", "a_pivot_mm[0] = 1e+308"},
        Case{"tool_ball_minus_1e6", R"("tool_ball_mm":[0,0,-1e6])", "tool_ball_mm[2] = -1000000"},
        Case{"tolerance_unknown_key", R"("tolerances":{"location_mm":0.02})", "unknown key \"location_mm\""},
        Case{"tolerance_zero", R"("tolerances":{"location_um":0})", "tolerances.location_um = 0"},
        Case{"tolerance_negative", R"("tolerances":{"angle_arcsec":-5})", "tolerances.angle_arcsec"},
        Case{"tolerance_mm_for_um", R"("tolerances":{"circularity_um":1e5})", "tolerances.circularity_um = 100000"},
        Case{"tolerance_not_a_number", R"("tolerances":{"location_um":"20"})", "must be a number"},
        Case{"tolerances_not_an_object", R"("tolerances":20)", "tolerances must be an object"},
        // found by fuzz_machine_file: a number past double escaped as nlohmann's out_of_range
        Case{"number_past_double", R"("travel":{"X_mm":[-844444443E88888,0]})", "not valid JSON"}),
    [](const auto& param_info) { return std::string(param_info.param.name); });

TEST(MachineFile, TheProjectsOwnMachineFilesStayValid) {
    for (const char* f : {"rrttt.json", "tttrr.json", "rtttr.json"}) {
        std::ifstream in(std::string(BALLBAR_TEST_DATA_DIR) + "/machines/" + f);
        std::stringstream ss;
        ss << in.rdbuf();
        EXPECT_NO_THROW(parse_machine_file(ss.str())) << f;
    }
}

TEST(MachineFile, TolerancesAreReadWrittenBackAndOptionalEachOnItsOwn) {
    const MachineFile m =
        parse_machine_file("{" + kMachine + R"(,"tolerances":{"location_um":20,"angle_arcsec":12.5}})");
    EXPECT_EQ(m.tolerances.location_um, 20.0);
    EXPECT_EQ(m.tolerances.angle_arcsec, 12.5);
    EXPECT_FALSE(m.tolerances.circularity_um.has_value());
    const MachineFile back = parse_machine_file(write_machine_file(m));
    EXPECT_EQ(back.tolerances.location_um, 20.0);
    EXPECT_EQ(back.tolerances.angle_arcsec, 12.5);
    EXPECT_FALSE(back.tolerances.circularity_um.has_value());
    // None given: none written, none read.
    const MachineFile none = parse_machine_file("{" + kMachine + "}");
    EXPECT_FALSE(none.tolerances.any());
    EXPECT_EQ(write_machine_file(none).find("tolerances"), std::string::npos);
}

// ---- plan files

const std::string kTests = R"("tests":[{"socket_mm":[-49.275,-14.312,-77.777],"rotation_deg":{"A":10,"C":30}}])";

class BadPlanFile : public ::testing::TestWithParam<Case> {};

TEST_P(BadPlanFile, IsRefusedNamingTheField) {
    const Case& c = GetParam();
    const std::string why = refusal([&] { parse_plan_file("{" + c.text + "}", MachineType::TTTRR); });
    EXPECT_EQ(why.rfind("plan file", 0), 0u) << why;
    EXPECT_NE(why.find(c.says), std::string::npos) << why;
}

INSTANTIATE_TEST_SUITE_P(
    Values, BadPlanFile,
    ::testing::Values(
        Case{"unknown_key", kTests + R"(,"dwel_s":2)", "unknown key \"dwel_s\""},
        Case{"unknown_capture_key", kTests + R"(,"capture":{"windows_s":0.5})", "capture: unknown key \"windows_s\""},
        Case{"unknown_answers_key", kTests + R"(,"answers":{"confirm":true})", "answers: unknown key \"confirm\""},
        Case{"unknown_test_key", R"("tests":[{"socket_mm":[0,0,0],"rotation_deg":{"A":10},"speed":3}])",
             "tests[0]: unknown key \"speed\""},
        Case{"dwell_1e308", kTests + R"(,"dwell_s":1e308)", "dwell_s = 1e+308"},
        Case{"dwell_shorter_than_two_windows", kTests + R"(,"dwell_s":0.9,"capture":{"window_s":0.5})",
             "dwell_s = 0.9 s: it must be at least two capture windows"},
        Case{"negative_retries", kTests + R"(,"capture":{"retries":-1})", "retries = -1 is not an integer in [0, 100]"},
        Case{"fractional_retries", kTests + R"(,"capture":{"retries":1.5})", "retries = 1.5"},
        Case{"zero_tolerance", kTests + R"(,"capture":{"tolerance_mm":0})", "tolerance_mm = 0 must be > 0"},
        Case{"zero_max_std", kTests + R"(,"capture":{"max_std_um":0})", "max_std_um = 0 must be > 0"},
        Case{"zero_max_drift", kTests + R"(,"capture":{"max_drift_um":0})", "max_drift_um = 0 must be > 0"},
        Case{"window_zero", kTests + R"(,"capture":{"window_s":0})", "window_s = 0 is outside"},
        Case{"window_1e308", kTests + R"(,"capture":{"window_s":1e308})", "window_s = 1e+308 is outside"},
        Case{"bar_length_1e308", kTests + R"(,"bar_length_mm":1e308)", "bar_length_mm = 1e+308"},
        Case{"bar_length_negative", kTests + R"(,"bar_length_mm":-100)", "bar_length_mm = -100"},
        Case{"max_condition_zero", kTests + R"(,"max_condition":0)", "max_condition = 0 is outside"},
        Case{"socket_1e308", R"("tests":[{"socket_mm":[1e308,0,0],"rotation_deg":{"A":10}}])", "socket_mm[0] = 1e+308"},
        Case{"rotation_1e308", R"("tests":[{"socket_mm":[0,0,0],"rotation_deg":{"A":1e308}}])",
             "rotation_deg.A = 1e+308"},
        Case{"confirm_not_boolean", kTests + R"(,"answers":{"confirm_setup":"yes"})",
             "confirm_setup must be true or false"},
        Case{"test_tolerance_zero",
             R"("tests":[{"socket_mm":[0,0,0],"rotation_deg":{"A":10},"tolerances":{"location_um":0}}])",
             "tests[0]: tolerances.location_um = 0"},
        Case{"test_tolerance_circularity",
             R"("tests":[{"socket_mm":[0,0,0],"rotation_deg":{"A":10},"tolerances":{"circularity_um":5}}])",
             "tests[0]: tolerances: unknown key \"circularity_um\""}),
    [](const auto& param_info) { return std::string(param_info.param.name); });

TEST(PlanFile, ATestsOwnTolerancesAreReadAndWrittenBack) {
    const PlanSpec spec = parse_plan_file(
        R"({"tests":[{"socket_mm":[0,0,-80],"rotation_deg":{"A":10},"tolerances":{"location_um":15}},
                     {"socket_mm":[0,0,-80],"rotation_deg":{"C":30}}]})",
        MachineType::TTTRR);
    EXPECT_EQ(spec.tests[0].tolerances.location_um, 15.0);
    EXPECT_FALSE(spec.tests[0].tolerances.angle_arcsec.has_value());
    EXPECT_FALSE(spec.tests[1].tolerances.any());
    const PlanSpec back = parse_plan_file(write_plan_file(spec, MachineType::TTTRR), MachineType::TTTRR);
    EXPECT_EQ(back.tests[0].tolerances.location_um, 15.0);
    EXPECT_FALSE(back.tests[1].tolerances.any());
}

TEST(PlanFile, TheProjectsOwnPlanFilesStayValid) {
    for (const char* f : {"tttrr-quick.plan.json", "tttrr-table2.plan.json", "tttrr-two-sockets.plan.json"}) {
        std::ifstream in(std::string(BALLBAR_TEST_DATA_DIR) + "/machines/" + f);
        std::stringstream ss;
        ss << in.rdbuf();
        EXPECT_NO_THROW(parse_plan_file(ss.str(), MachineType::TTTRR)) << f;
    }
}

TEST(PlanSpec, MakePlanAppliesTheSameRanges) {
    const MachineFile m = seed_machine(MachineType::TTTRR);
    PlanSpec s = default_plan(m);
    s.capture.retries = -2;
    EXPECT_NE(refusal([&] { make_plan(m, s); }).find("retries = -2"), std::string::npos);
    s = default_plan(m);
    s.dwell_s = 2 * s.capture.window_s - 0.01;
    EXPECT_NE(refusal([&] { make_plan(m, s); }).find("two capture windows"), std::string::npos);
    s.dwell_s = 2 * s.capture.window_s;
    EXPECT_EQ(refusal([&] { make_plan(m, s); }), "accepted");
}

TEST(NcProgramWords, APositionBeyondTheWordFormatIsAPlanError) {
    MachineFile m = seed_machine(MachineType::TTTRR);
    m.travel = {};  // unlimited travel: only the word format stops it
    PlanSpec s = default_plan(m);
    for (auto& t : s.tests) t.socket_mm.x() = 99'990;  // the tool ball's X passes 100 000 mm
    const Plan plan = make_plan(m, s);
    const std::string why = refusal([&] { write_plan_program(plan, 0); });
    EXPECT_NE(why.find("NC word X"), std::string::npos) << why;
}

}  // namespace
}  // namespace ballbar::acquisition
