// SPDX-License-Identifier: MIT
// Stored result payloads, in the shapes acquisition/result_codec.hpp, `ballbar identify` and
// `ballbar discover` write them, become report content.
#include <gtest/gtest.h>

#include "ballbar/report/results.hpp"

namespace ballbar::report {
namespace {

using nlohmann::json;

Report tttrr() {
    Report r;
    r.header.machine.type = analysis::MachineType::TTTRR;
    return r;
}

TEST(Results, SsmOfTheAcquisition) {
    Report r = tttrr();
    ASSERT_TRUE(add_result(r, "ssm", json::parse(R"({"condition_number":1.0,"dV_mm":[-0.0075,-0.0207,0.0118],
        "datum_mm":[-49.275,-14.312,-177.777],"e_exact_mm":[-0.0075,-0.0207,0.0118],"e_linear_mm":[-0.0075,-0.0207,0.0118],
        "e_std_mm":[4.9e-06,4.8e-06,5e-06],"n":3,"step":2,"test":1})")));
    ASSERT_EQ(r.locations.size(), 1u);
    const auto& l = r.locations[0];
    EXPECT_EQ(l.location, 3);  // 2·test + step − 1, as the acquisition numbers the points
    EXPECT_NEAR(l.error_um.x(), -7.5, 1e-12);
    EXPECT_NEAR(l.uncertainty_um.z(), 0.005, 1e-12);
    EXPECT_EQ(l.points, 3);
    EXPECT_EQ(l.label, "test 2 step 2, after rotation");  // "test":1 is the second test
}

TEST(Results, OrientationGivesTheTypesAngles) {
    Report r = tttrr();
    add_result(r, "orientation", json::parse(R"({"test":0,"kind":"BothAxes","dV1_mm":[0,0,0],"dV2_mm":[0,0,0],
        "first_order":{"d_alpha_rad":1e-4,"d_beta_rad":0,"d_gamma_rad":2e-4},"exact":null,"std":null,"singular":"exact: S0 = 0"})"));
    ASSERT_EQ(r.orientation.size(), 2u);
    EXPECT_EQ(r.orientation[0].symbol, "Δα");
    EXPECT_EQ(r.orientation[1].symbol, "Δγ");
    EXPECT_DOUBLE_EQ(*r.orientation[1].first_order_rad, 2e-4);
    EXPECT_FALSE(r.orientation[1].exact_rad.has_value());  // singular: shown as "–", not as 0
    EXPECT_EQ(r.orientation[0].to_location, 1);
}

TEST(Results, AcquisitionTransitionsBecomeTheProcedure) {
    Report r = tttrr();
    add_result(
        r, "acquisition.transition",
        json::parse(R"({"from":"Step1Capture","to":"Step1Capture","event":"PointRejected","detail":"std 3 µm"})"));
    add_result(r, "acquisition.transition",
               json::parse(R"({"from":"Step1Capture","to":"Paused","event":"DeviceLost","detail":""})"));
    ASSERT_EQ(r.procedure.size(), 2u);
    EXPECT_EQ(r.procedure[0].kind, "repeat");
    EXPECT_EQ(r.procedure[0].detail, "std 3 µm");
    EXPECT_EQ(r.procedure[1].kind, "pause");
    EXPECT_EQ(r.procedure[1].step, "Paused");
}

TEST(Results, IdentifyConvertsToDisplayUnits) {
    Report r = tttrr();
    add_result(r, "identification", json::parse(R"({"converged":true,"iterations":4,"initial_rms_um":9.5,
        "residual_rms_um":0.4,"estimates":[
          {"name":"X0C","estimate":0.012,"std":0.0004,"unit":"mm","independence":0.8,"observable":true},
          {"name":"A0C","estimate":1e-5,"std":1e-6,"unit":"rad","independence":0.5,"observable":true},
          {"name":"C_zero","estimate":0,"std":0,"unit":"rad","independence":0,"observable":false}]})"));
    ASSERT_TRUE(r.model.has_value());
    ASSERT_EQ(r.model->parameters.size(), 3u);
    EXPECT_NEAR(r.model->parameters[0].value, 12.0, 1e-9);
    EXPECT_EQ(r.model->parameters[0].unit, "µm");
    EXPECT_NEAR(r.model->parameters[1].value, 2.0626480624709636, 1e-9);  // 1e-5 rad in arcsec
    EXPECT_EQ(r.model->parameters[1].unit, "arcsec");
    EXPECT_FALSE(r.model->parameters[2].note.empty());
    EXPECT_DOUBLE_EQ(*r.model->residual_rms_before_um, 9.5);
}

TEST(Results, DiscoverStepsWithBinnedTrends) {
    Report r = tttrr();
    add_result(r, "discovery", json::parse(R"({"steps":[{"effect":"spindle_growth","iso":"","estimate":0.004,
        "unit":"mm/h","stderr":0.0002,"rms_before_um":3.1,"rms_after_um":0.5,"explained_by":"time"}],
        "details":{"residuals_initial":[{"variable":"time","r2":0.9,"bin_centre":[10,20,30],"bin_mean_um":[-2,0,2]}],
                   "residuals_final":[{"variable":"time","r2":0.1,"bin_centre":[10,20,30],"bin_mean_um":[0.1,0,-0.1]}]}})"));
    ASSERT_EQ(r.discovery.size(), 1u);
    const auto& d = r.discovery[0];
    EXPECT_TRUE(d.binned);
    EXPECT_EQ(d.variable, "session time");
    EXPECT_EQ(d.variable_unit, "s");
    EXPECT_EQ(d.x.size(), 3u);
    EXPECT_DOUBLE_EQ(d.before_um[2], 2);
    EXPECT_DOUBLE_EQ(*d.rms_after_um, 0.5);
    EXPECT_NE(d.note.find("µm/h"), std::string::npos) << d.note;
}

TEST(Results, MalformedPayloadsNameTheKey) {
    Report r = tttrr();
    try {
        add_result(r, "compensation",
                   json::parse(R"({"metric":"m","axes":[{"axis":"X","unit":"µm","before":"big","after":1}]})"));
        FAIL() << "no error";
    } catch (const ReportError& e) {
        EXPECT_NE(std::string(e.what()).find("before"), std::string::npos) << e.what();
    }
    EXPECT_THROW(add_result(r, "ssm", json::array()), ReportError);
    // The stored plan: read for its machine file's tolerances alone.
    EXPECT_TRUE(add_result(r, "acquisition.plan", json::object()));
    EXPECT_FALSE(r.location_tolerance_um.has_value());
    EXPECT_TRUE(add_result(r, "acquisition.plan", json::parse(R"({"machine":{"tolerances":{"location_um":20}}})")));
    EXPECT_EQ(r.location_tolerance_um, 20.0);
    EXPECT_EQ(r.location_tolerance_source, "the machine file, stored with the session");
    EXPECT_FALSE(r.angle_tolerance_arcsec.has_value());
    try {
        add_result(r, "acquisition.plan", json::parse(R"({"machine":{"tolerances":{"angle_arcsec":-3}}})"));
        FAIL() << "no error";
    } catch (const ReportError& e) {
        EXPECT_NE(std::string(e.what()).find("angle_arcsec"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace ballbar::report
