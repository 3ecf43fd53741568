// SPDX-License-Identifier: MIT
// The procedure's stored results ("ssm", "orientation", "acquisition.plan"): documents written by hand
// from docs/storage.md are read to their values, what is written reads back to the last bit, and a
// payload of another shape is refused naming the key.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "ballbar/acquisition/result_codec.hpp"

namespace ballbar::acquisition {
namespace {

TEST(ResultCodec, ReadsAnSsmResultAsStored) {
    const LocationResult r = location_from_json(
        R"({"test":1,"step":2,"datum_mm":[-49.275,-14.312,-177.777],"e_exact_mm":[-0.0075,-0.0207,0.0118],)"
        R"("e_linear_mm":[-0.0074,-0.0206,0.0117],"e_std_mm":[4.9e-06,4.8e-06,5e-06],)"
        R"("dV_mm":[0.0075,0.0207,-0.0118],"condition_number":1.25,"n":3})");
    EXPECT_EQ(r.test, 1);
    EXPECT_EQ(r.step, 2);
    EXPECT_DOUBLE_EQ(r.datum_mm.z(), -177.777);
    EXPECT_DOUBLE_EQ(r.ssm.exact_mm.y(), -0.0207);
    EXPECT_DOUBLE_EQ(r.ssm.linear_mm.x(), -0.0074);
    EXPECT_DOUBLE_EQ(r.ssm.std_mm.z(), 5e-06);
    EXPECT_DOUBLE_EQ(r.dV_mm.z(), -0.0118);
    EXPECT_DOUBLE_EQ(r.ssm.condition_number, 1.25);
    EXPECT_EQ(r.ssm.n, 3u);
    EXPECT_FALSE(r.ssm.residual_rms_mm.has_value());
}

TEST(ResultCodec, WhatIsWrittenReadsBackToTheLastBit) {
    LocationResult l;
    l.test = 3;
    l.step = 1;
    l.datum_mm = {1.0 / 3, -2.0 / 7, 100.1};
    l.ssm.exact_mm = {1e-3 / 3, 2e-3 / 7, -5e-4};
    l.ssm.linear_mm = {1e-3 / 9, 0, 1e-17};
    l.ssm.std_mm = {1e-6 / 3, 2e-6, 3e-6};
    l.ssm.condition_number = std::numeric_limits<double>::infinity();  // a degenerate layout: null
    l.ssm.n = 12;
    l.ssm.residual_rms_mm = 1.0 / 3e4;
    l.dV_mm = -l.ssm.exact_mm;
    const LocationResult lb = location_from_json(location_to_json(l));
    EXPECT_EQ(lb.datum_mm, l.datum_mm);
    EXPECT_EQ(lb.ssm.exact_mm, l.ssm.exact_mm);
    EXPECT_EQ(lb.ssm.linear_mm, l.ssm.linear_mm);
    EXPECT_EQ(lb.ssm.std_mm, l.ssm.std_mm);
    EXPECT_EQ(lb.dV_mm, l.dV_mm);
    EXPECT_TRUE(std::isinf(lb.ssm.condition_number));
    EXPECT_EQ(lb.ssm.residual_rms_mm, l.ssm.residual_rms_mm);
    EXPECT_EQ(location_to_json(lb), location_to_json(l));

    TestResult t;
    t.test = 2;
    t.kind = TestKind::SpindleBeta;
    t.dV1_mm = {1e-3 / 3, 0, 0};
    t.dV2_mm = {0, -1e-3 / 7, 0};
    t.orientation.first_order = analysis::OrientationErrors{1e-5 / 3, 2e-5 / 3, -1e-6};
    t.orientation.singular = "exact: S0 = 0";
    const TestResult tb = test_from_json(test_to_json(t));
    EXPECT_EQ(tb.kind, TestKind::SpindleBeta);
    EXPECT_EQ(tb.dV2_mm, t.dV2_mm);
    ASSERT_TRUE(tb.orientation.first_order.has_value());
    EXPECT_EQ(tb.orientation.first_order->d_beta_rad, 2e-5 / 3);
    EXPECT_FALSE(tb.orientation.exact.has_value()) << "singular: null, not zeros";
    EXPECT_FALSE(tb.std_rad.has_value());
    EXPECT_EQ(tb.orientation.singular, "exact: S0 = 0");
    EXPECT_EQ(test_to_json(tb), test_to_json(t));
}

TEST(ResultCodec, APayloadOfAnotherShapeIsRefusedNamingTheKey) {
    const std::string ssm =
        R"("test":0,"step":1,"datum_mm":[0,0,0],"e_exact_mm":[0,0,0],"e_linear_mm":[0,0,0],"e_std_mm":[0,0,0],)"
        R"("dV_mm":[0,0,0],"condition_number":1,"n":3)";
    const struct {
        std::string text, says;
    } ssm_cases[] = {
        {"[]", "must be a JSON object"},
        {"{" + ssm + R"(,"std_mm":[0,0,0]})", "\"std_mm\" is not a key it has"},
        {R"({"test":0,"step":1})", "\"datum_mm\" is missing"},
        {"{" + ssm.substr(0, ssm.find(R"("dV_mm")")) + R"("dV_mm":[1,2],"condition_number":1,"n":3})",
         "\"dV_mm\" must be an array of three numbers"},
        {R"({"test":0,"step":3,"datum_mm":[0,0,0]})", "\"step\" must be 1 or 2"},
        {R"({"test":-1})", "\"test\" must be a non-negative integer"},
        {"{" + ssm.substr(0, ssm.find(R"("n")")) + R"("n":2.5})", "\"n\" must be a non-negative integer"},
    };
    for (const auto& c : ssm_cases) {
        try {
            (void)location_from_json(c.text);
            ADD_FAILURE() << "accepted " << c.text;
        } catch (const ResultFormatError& e) {
            EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << e.what() << " / wanted: " << c.says;
            EXPECT_NE(std::string(e.what()).find("result \"ssm\""), std::string::npos) << e.what();
        }
    }
    const std::string o = R"("test":0,"dV1_mm":[0,0,0],"dV2_mm":[0,0,0],"first_order":null,"exact":null,"std":null)";
    EXPECT_THROW((void)test_from_json("{" + o + R"(,"kind":"spindle-beta"})"), ResultFormatError);
    EXPECT_THROW((void)test_from_json(R"({"kind":"BothAxes",)" + o.substr(0, o.find(R"("exact")")) +
                                      R"("exact":{"d_alpha_rad":1},"std":null})"),
                 ResultFormatError);
    EXPECT_NO_THROW((void)test_from_json("{" + o + R"(,"kind":"TableAlpha"})"));
}

}  // namespace
}  // namespace ballbar::acquisition
