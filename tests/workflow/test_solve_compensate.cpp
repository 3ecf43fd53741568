// SPDX-License-Identifier: MIT
// The JSON services, the compensation of a program and the compensation proof as use cases, in process.
// The SSM request's readings are computed here from the bar's geometry alone (the length between the
// socket and a tool ball displaced by a known error); the compensated program is checked against the
// rotation about a displaced C axis worked out by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "../scratch_dir.hpp"
#include "ballbar/storage/model_codec.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/workflow/compensate.hpp"
#include "ballbar/workflow/compensation_demo.hpp"
#include "ballbar/workflow/error.hpp"
#include "ballbar/workflow/solve.hpp"

namespace ballbar::workflow {
namespace {

using nlohmann::json;

/// The field a refused request blames.
std::string refused_field(SolveService service, const std::string& request) {
    try {
        solve(service, request);
    } catch (const SolveError& e) {
        EXPECT_EQ(e.category(), ErrorCategory::bad_input);
        return e.field();
    }
    ADD_FAILURE() << "not refused: " << request;
    return "(accepted)";
}

TEST(SolveService, SsmFindsTheToolBallsDisplacementFromTheBarLengths) {
    const double e[3] = {0.010, -0.020, 0.005};  // mm: where the tool ball really is, minus where it should be
    const std::vector<std::vector<double>> points = {
        {100, 0, 0}, {0, 100, 0}, {0, 0, 100}, {-70.7, 0, 70.7}, {0, -70.7, 70.7}};
    json req{{"socket_mm", {0, 0, 0}}, {"points_mm", points}, {"delta_l_mm", json::array()}};
    for (const auto& p : points) {
        const double nominal = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        const double actual =
            std::sqrt((p[0] + e[0]) * (p[0] + e[0]) + (p[1] + e[1]) * (p[1] + e[1]) + (p[2] + e[2]) * (p[2] + e[2]));
        req["delta_l_mm"].push_back(actual - nominal);
    }
    const json answer = json::parse(solve(SolveService::ssm, req.dump()));
    for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(answer["exact_mm"][i].get<double>(), e[i], 1e-9) << i;
    EXPECT_TRUE(answer["residual_rms_mm"].is_number());
    EXPECT_TRUE(answer["iterations"].is_number_integer());
}

TEST(SolveService, ARefusedRequestNamesItsField) {
    const std::string ok_points = R"("socket_mm":[0,0,0],"points_mm":[[100,0,0],[0,100,0],[0,0,100]])";
    EXPECT_EQ(refused_field(SolveService::ssm, "{" + ok_points + "}"), "delta_l_mm");
    EXPECT_EQ(refused_field(SolveService::ssm, "{" + ok_points + R"(,"delta_l_mm":[0,0,"x"]})"), "delta_l_mm[2]");
    EXPECT_EQ(refused_field(SolveService::ssm, "{" + ok_points + R"(,"delta_l_mm":[0,0,0],"extra":1})"), "extra");
    EXPECT_EQ(refused_field(SolveService::ssm, R"({"socket_mm":[0,0,0],"points_mm":[[100,0,0],[0,100,0],[0,0,"z"]],
                                                   "delta_l_mm":[0,0,0]})"),
              "points_mm[2][2]");
    EXPECT_EQ(refused_field(SolveService::ssm, "{\"socket_mm\": "), "");
    EXPECT_EQ(refused_field(SolveService::orientation, R"({"machine":"RTTTR","spindle":{"pivot_mm":[0,0,0],
              "tool_ball_mm":[0,0,-250],"beta_rad":0.5,"dV1_mm":[0,0,0],"dV2_mm":[0,0,0],"gamma":1}})"),
              "spindle.gamma");
    EXPECT_EQ(refused_field(SolveService::compensate, R"({"kinematics":"lei-hsu","u":[0,0,0,0.5,0.3],
              "dv":[0,0,0,0,0,0],"offsets_mm":{"Q":1}})"),
              "offsets_mm.Q");
    EXPECT_EQ(refused_field(SolveService::compensate, R"({"kinematics":"lei-hsu","u":[0,0,0,0.5,1e9],
              "dv":[0,0,0,0,0,0]})"),
              "u[4]");
}

TEST(SolveService, NoPoseErrorNeedsNoCorrection) {
    const json answer = json::parse(
        solve(SolveService::compensate, R"({"kinematics":"lei-hsu","u":[10,20,30,0.5,0.3],"dv":[0,0,0,0,0,0]})"));
    for (const char* key : {"du_mm", "du_rad", "exact_du_mm", "exact_du_rad"})
        for (const auto& v : answer[key]) EXPECT_NEAR(v.get<double>(), 0.0, 1e-12) << key;
    EXPECT_FALSE(answer["singular"].get<bool>());
}

/// A TTTRR model whose C axis line is off by `x0c_mm` in X.
storage::ErrorModel c_axis_off(double x0c_mm) {
    storage::ErrorModel m;
    m.machine.type = analysis::MachineType::TTTRR;
    m.machine.name = "DL-5X";
    m.machine.c_offset_mm = {0, 0, -100};
    m.params.push_back({analysis::Param::X0C, x0c_mm, std::nullopt});
    return m;
}

TEST(CompensateUseCase, TheModelIsFoundByFileByIdAndByNameAndAMissingOneIsSaid) {
    test::ScratchDir d{"compensate-wf"};
    const std::string model_json = storage::model_to_json(c_axis_off(0.02));
    const std::string file = d.write("model.json", model_json);
    EXPECT_EQ(find_model(file, d.file("none.db")).source, file);
    const std::string db = d.file("test.db");
    {
        storage::Store store(db);
        store.save_model("DL-5X", model_json);
        store.save_model("DL-5X", storage::model_to_json(c_axis_off(0.03)));
    }
    const ModelChoice by_name = find_model("DL-5X", db);
    EXPECT_EQ(by_name.source, "model DL-5X v2");
    EXPECT_DOUBLE_EQ(by_name.model.values()[analysis::Param::X0C], 0.03);
    EXPECT_DOUBLE_EQ(find_model("1", db).model.values()[analysis::Param::X0C], 0.02);
    for (const std::string& missing : {std::string("7"), std::string("no-such-model")}) {
        try {
            find_model(missing, db);
            ADD_FAILURE() << missing;
        } catch (const Error& e) {
            EXPECT_EQ(e.category(), ErrorCategory::bad_input) << e.what();
        }
    }
    try {
        find_model("DL-5X", d.file("absent.db"), " (check --db)");
        ADD_FAILURE();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("no database at"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("(check --db)"), std::string::npos) << e.what();
    }
}

TEST(CompensateUseCase, AProgramAtC90IsMovedByTheDisplacedAxisRotation) {
    // Rotating a point by 90° about an axis displaced by d moves it by (I − R)·d, of length √2·|d|.
    const double d_mm = 0.02;
    const ModelChoice model{c_axis_off(d_mm), "test model"};
    std::string written;
    ProgramCompensation pc;
    const analysis::NcCompensateSummary s =
        compensate_program(model, "%\nG90 G1 X50 Y0 Z0 A0 C0 F1000\nG1 C90\nM30\n%\n", "part.nc", pc,
                           [&](std::string_view chunk) { written += chunk; });
    EXPECT_EQ(s.moves, 2u);
    EXPECT_NEAR(s.max_linear_mm, std::sqrt(2.0) * d_mm, 1e-4) << written;
    EXPECT_NE(written.find("compensated by ballbar with test model"), std::string::npos) << written;
    EXPECT_EQ(program_dialect(pc, "part.ngc"), analysis::NcDialect::LinuxCNC);
    EXPECT_EQ(program_dialect(pc, "part.nc"), analysis::NcDialect::Fanuc);
    pc.controller = "acme";
    EXPECT_THROW(compensate_program(model, "%\nG1 X1\nM30\n%\n", "part.nc", pc, [](std::string_view) {}), Error);
}

TEST(CompensationDemoUseCase, TheIdentifiedModelCutsThePathErrorOnEveryAxis) {
    CompensationDemoOptions o;
    o.path_points = 72;
    const CompensationDemo demo = run_compensation_demo(o);
    ASSERT_TRUE(demo.fit.converged);
    EXPECT_EQ(demo.path_blocks, 72);
    for (int a = 0; a < 3; ++a) {
        EXPECT_GT(demo.rms_before_um[a], 1.0) << a;  // the seed-like errors are tens of µm
        EXPECT_GT(demo.improvement(a), 5.0)
            << "axis " << a << ": " << demo.rms_before_um[a] << " -> " << demo.rms_after_um[a];
    }
    // Judged against what the plan can identify, every estimate agrees within 5σ.
    ASSERT_FALSE(demo.identified.empty());
    for (const auto& p : demo.identified) {
        if (!(p.estimate.std > 0)) continue;
        EXPECT_LT(std::abs(p.estimate.estimate - p.identifiable_value) / p.estimate.std, 5.0) << p.estimate.name;
    }
}

}  // namespace
}  // namespace ballbar::workflow
