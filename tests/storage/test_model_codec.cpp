// SPDX-License-Identifier: MIT
// The stored error model, ballbar-model/1: documents written by hand from docs/identification.md are
// read to the values they hold, what is written reads back exactly, and what the format does not allow
// is refused naming the key.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "ballbar/storage/identification_codec.hpp"
#include "ballbar/storage/machine_json.hpp"
#include "ballbar/storage/model_codec.hpp"
#include "ballbar/storage/offsets_codec.hpp"

namespace ballbar::storage {
namespace {

using analysis::Param;

const std::string kMachine =
    R"("machine":{"type":"TTTRR","name":"m1","a_pivot_mm":[0,0,-50],"c_offset_mm":[0,0,-100],"tool_ball_mm":[0,0,-200]})";

TEST(ModelCodec, ReadsTheDocumentedDocument) {
    const ErrorModel m = model_from_json(R"({"format":"ballbar-model/1",)" + kMachine + R"(,
        "params":{"X0C":0.035,"B0C":-2e-5},"std":{"X0C":3.3e-5},"unobservable":["A_zero"],
        "sockets":[{"nominal_mm":[100,0,0],"offset_mm":[0.001,-0.002,0]}],
        "residual_rms_um":0.09,"readings":66,"converged":true})");
    EXPECT_EQ(m.machine.type, analysis::MachineType::TTTRR);
    EXPECT_EQ(m.machine.name, "m1");
    EXPECT_DOUBLE_EQ(m.machine.c_offset_mm.z(), -100);
    ASSERT_EQ(m.params.size(), 2u);
    EXPECT_EQ(m.params[0].param, Param::X0C);
    EXPECT_DOUBLE_EQ(m.params[0].value, 0.035);
    ASSERT_TRUE(m.params[0].std.has_value());
    EXPECT_DOUBLE_EQ(*m.params[0].std, 3.3e-5);
    EXPECT_FALSE(m.params[1].std.has_value());
    const analysis::ErrorParams v = m.values();
    EXPECT_DOUBLE_EQ(v[Param::X0C], 0.035);
    EXPECT_DOUBLE_EQ(v[Param::B0C], -2e-5);
    EXPECT_DOUBLE_EQ(v[Param::Y0C], 0.0) << "parameters the model does not hold are 0";
    ASSERT_EQ(m.unobservable.size(), 1u);
    EXPECT_EQ(m.unobservable[0], Param::A_zero);
    ASSERT_EQ(m.sockets.size(), 1u);
    EXPECT_DOUBLE_EQ(m.sockets[0].offset_mm.y(), -0.002);
    EXPECT_EQ(m.readings, 66);
    EXPECT_EQ(m.converged, true);
    EXPECT_DOUBLE_EQ(m.residual_rms_um.value_or(-1), 0.09);
}

TEST(ModelCodec, AModelStoredBeforeTheFormatKeyAndDiscoverysVersionsAreRead) {
    const ErrorModel m = model_from_json(
        "{" + kMachine + R"(,"params":{"X0C":0.01},"empirical":{"C_angular_h1_cos":1e-5},"added":"C_angular"})");
    ASSERT_EQ(m.empirical.size(), 1u);
    EXPECT_EQ(m.empirical[0].term.name(), "C_angular_h1_cos");
    EXPECT_DOUBLE_EQ(m.empirical[0].value, 1e-5);
    EXPECT_EQ(m.added, "C_angular");
}

TEST(ModelCodec, WhatIsWrittenReadsBackExactly) {
    ErrorModel m;
    m.machine = machine_from_json(R"({"type":"RTTTR","a_pivot_mm":[1.5,0,-50],"tool_ball_mm":[0,0,-150.25]})");
    m.params = {{Param::X0C, 0.1 / 3.0, 1e-7 / 3.0}, {Param::A_zero, -1.0 / 7e5, std::nullopt}};
    m.unobservable = {Param::C0A};
    m.sockets = {{analysis::Vec3(1, 2, 3), analysis::Vec3(1e-3 / 3, 0, -2e-4)}};
    m.residual_rms_um = 0.123456789;
    m.readings = 123;
    m.converged = false;
    analysis::PoseRange measured;  // where it was measured: read back as written (angles in degrees)
    measured.add({-12.5, 0, 3, analysis::deg_to_rad(-30), 0, 0});
    measured.add({40.25, 1, 2, analysis::deg_to_rad(45), 0, analysis::deg_to_rad(300)});
    m.measured_poses = measured;
    const std::string text = model_to_json(m);
    EXPECT_NE(
        text.find(R"("measured_poses":{"X_mm":[-12.5,40.25],"Y_mm":[0.0,1.0],"Z_mm":[2.0,3.0],"A_deg":[-30.0,45.0])"),
        std::string::npos)
        << text;
    EXPECT_EQ(text.rfind(R"({"format":"ballbar-model/1",)", 0), 0u) << text;
    const ErrorModel back = model_from_json(text);
    EXPECT_EQ(model_to_json(back), text);
    EXPECT_EQ(back.params[0].value, 0.1 / 3.0) << "to the last bit";
    EXPECT_EQ(*back.params[0].std, 1e-7 / 3.0);
    EXPECT_EQ(back.params[1].value, -1.0 / 7e5);
    EXPECT_EQ(back.sockets[0].offset_mm.x(), 1e-3 / 3);
    EXPECT_EQ(back.machine.a_pivot_mm.x(), 1.5);
    ASSERT_TRUE(back.measured_poses.has_value());
    EXPECT_EQ(back.measured_poses->max[5], analysis::deg_to_rad(300.0));
}

TEST(ModelCodec, RefusesWhatTheFormatDoesNotAllowNamingTheKey) {
    const std::string p = R"("params":{"X0C":0.01})";
    const struct {
        std::string text, says;
    } cases[] = {
        {"[1]", "must be a JSON object"},
        {"{" + kMachine + "," + p + ",", "malformed JSON"},
        {R"({"format":"ballbar-model/2",)" + kMachine + "," + p + "}", "is not ballbar-model/1"},
        {"{" + p + "}", "no \"machine\""},
        {"{" + kMachine + "}", "\"params\" must be an object"},
        {"{" + kMachine + "," + p + R"(,"parms":{}})", "parms: unknown key"},
        {"{" + kMachine + R"(,"params":{"X9Q":1}})", "params.X9Q: unknown parameter"},
        {"{" + kMachine + R"(,"params":{"X0C":"1"}})", "params.X0C: must be a finite number"},
        {"{" + kMachine + R"(,"params":{"X0C":1e308}})", "params.X0C"},
        {"{" + kMachine + "," + p + R"(,"std":{"X0C":-1}})", "std.X0C: an uncertainty cannot be negative"},
        {"{" + kMachine + "," + p + R"(,"std":{"Y0C":1e-6}})", "std.Y0C: the model holds no value"},
        {"{" + kMachine + "," + p + R"(,"unobservable":"A_zero"})", "\"unobservable\" must be an array"},
        {"{" + kMachine + "," + p + R"(,"empirical":{"C_wobble":1}})", "empirical.C_wobble: unknown term"},
        {"{" + kMachine + "," + p + R"(,"sockets":[{"nominal_mm":[1,2]}]})", "sockets[0]"},
        {"{" + kMachine + "," + p + R"(,"readings":6.5})", "readings: must be a non-negative integer"},
        {"{" + kMachine + "," + p + R"(,"converged":1})", "converged: must be true or false"},
        {R"({"machine":{"type":"XYZ"},)" + p + "}", "machine.type"},
        {"{" + kMachine + "," + p + R"(,"measured_poses":{"X_mm":[0,1]}})", "measured_poses: must be"},
        {"{" + kMachine + "," + p +
             R"(,"measured_poses":{"X_mm":[0,1],"Y_mm":[0,1],"Z_mm":[0,1],"A_deg":[5,1],"B_deg":[0,0],"C_deg":[0,0]}})",
         "measured_poses.A_deg"},
    };
    for (const auto& c : cases) {
        try {
            (void)model_from_json(c.text);
            ADD_FAILURE() << "accepted: " << c.text;
        } catch (const FormatError& e) {
            EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << e.what() << "\n  for " << c.text;
        }
    }
}

}  // namespace
}  // namespace ballbar::storage

namespace ballbar::storage {
namespace {

// The offsets table, ballbar-nc-offsets/1 (docs/compensation.md, "The offsets table").
TEST(OffsetsCodec, ReadsTheDocumentedTableAndWritesItBack) {
    const analysis::NcOffsetTable t = offsets_from_json(R"({"format": "ballbar-nc-offsets/1",
        "work_offsets": {"G54": {"X_mm": 10, "Y_mm": -5, "Z_mm": -80, "A_deg": 0, "C_deg": 90},
                         "G59.1": {"Z_mm": 1.5}},
        "tools": {"1": {"length_mm": 80}}, "measured_tool_length_mm": 50})");
    ASSERT_EQ(t.work.size(), 2u);
    EXPECT_DOUBLE_EQ(t.work.at("G54").Y_mm, -5);
    EXPECT_DOUBLE_EQ(t.work.at("G54").C_rad, analysis::kPi / 2);
    EXPECT_DOUBLE_EQ(t.work.at("G59.1").X_mm, 0) << "missing axes are 0";
    EXPECT_DOUBLE_EQ(t.tool_length_mm.at(1), 80);
    EXPECT_DOUBLE_EQ(t.measured_tool_length_mm, 50);
    const analysis::NcOffsetTable back = offsets_from_json(offsets_to_json(t));
    EXPECT_EQ(offsets_to_json(back), offsets_to_json(t));
    EXPECT_NEAR(back.work.at("G54").C_rad, t.work.at("G54").C_rad, 1e-15);
}

TEST(OffsetsCodec, RefusesWhatTheFormatDoesNotAllowNamingTheKey) {
    const struct {
        const char* text;
        const char* says;
    } cases[] = {
        {R"({"format": "ballbar-nc-offsets/2"})", "is not ballbar-nc-offsets/1"},
        {R"({"work_offsets": {"G60": {}}})", "work_offsets.G60: not G54"},
        {R"({"work_offsets": {"G54": {"U_mm": 1}}})", "work_offsets.G54: unknown key \"U_mm\""},
        {R"({"work_offsets": {"G54": {"X_mm": 1e9}}})", "work_offsets.G54.X_mm"},
        {R"({"tools": {"T1": {"length_mm": 1}}})", "tools.T1: the key must be a tool number"},
        {R"({"tools": {"1": {"length_mm": 1, "radius_mm": 2}}})", "tools.1 must be"},
        {R"({"offsets": {}})", "unknown key \"offsets\" (known: format, work_offsets"},
        {R"([1, 2])", "must be a JSON object"},
    };
    for (const auto& c : cases) {
        try {
            (void)offsets_from_json(c.text);
            ADD_FAILURE() << "accepted " << c.text;
        } catch (const FormatError& e) {
            EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << e.what();
        }
    }
}

}  // namespace
}  // namespace ballbar::storage

namespace ballbar::storage {
namespace {

// The identification result (docs/identification.md): what `identify --json` prints and stores.
TEST(IdentificationCodec, ReadsAResultAsIdentifyWritesItAndOneStoredBeforeTheNoiseFloor) {
    const IdentificationRecord r = identification_from_json(R"({"converged":true,"iterations":4,"message":"ok",
        "readings":90,"degrees_of_freedom":81,"residual_rms_um":0.09,"residual_sigma_um":0.1,"initial_rms_um":30.5,
        "estimates":[{"name":"X0C","estimate":0.03,"std":1e-5,"sensitivity":0.9,"independence":0.8,"observable":true,
                      "unit":"mm"},
                     {"name":"C_zero","estimate":0,"std":0,"sensitivity":0,"independence":0,"observable":false,
                      "unit":"rad"}],
        "correlation":[[1]],"correlation_names":["X0C"]})");
    EXPECT_TRUE(r.converged);
    EXPECT_EQ(r.readings, 90);
    EXPECT_DOUBLE_EQ(r.initial_rms_um.value_or(0), 30.5);
    EXPECT_FALSE(r.noise_floor_um.has_value()) << "stored before the noise floor was written";
    ASSERT_EQ(r.estimates.size(), 2u);
    EXPECT_EQ(r.estimates[1].unit, "rad");
    EXPECT_FALSE(r.estimates[1].observable);
    EXPECT_FALSE(r.model.has_value());
}

TEST(IdentificationCodec, WhatTheFitWritesReadsBack) {
    analysis::FitSummary fit;
    fit.converged = true;
    fit.iterations = 3;
    fit.readings = 12;
    fit.residual_rms_mm = 1e-4 / 3;
    fit.noise_floor_mm = 1e-5;
    analysis::ParamEstimate e;
    e.name = "Y0C";
    e.param = analysis::Param::Y0C;
    e.estimate = -0.02 / 3;
    e.std = 1e-6;
    e.observable = true;
    fit.estimates = {e};
    fit.fitted = {0};
    fit.correlation = Eigen::MatrixXd::Identity(1, 1);
    ErrorModel m;
    m.machine.type = analysis::MachineType::TTTRR;
    m.params = {{analysis::Param::Y0C, e.estimate, e.std}};
    const IdentificationRecord r = identification_from_json(identification_to_json(fit, m));
    EXPECT_EQ(r.residual_rms_um, 1e-4 / 3 * 1e3);
    EXPECT_EQ(r.noise_floor_um.value_or(0), 1e-2);
    ASSERT_EQ(r.estimates.size(), 1u);
    EXPECT_EQ(r.estimates[0].estimate, -0.02 / 3);
    EXPECT_EQ(r.estimates[0].unit, "mm");
    ASSERT_TRUE(r.model.has_value());
    EXPECT_EQ(r.model->values()[analysis::Param::Y0C], -0.02 / 3);
    ASSERT_EQ(r.correlation.size(), 1u);
    EXPECT_EQ(r.correlation[0][0], 1.0);
}

TEST(IdentificationCodec, APayloadOfAnotherShapeIsRefusedNamingTheKey) {
    const std::string ok = R"("converged":true,"residual_rms_um":0.1,"estimates":[])";
    const struct {
        std::string text, says;
    } cases[] = {
        {R"({"residual_rms_um":0.1,"estimates":[]})", "\"converged\" is missing"},
        {"{" + ok + R"(,"rms_um":1})", "\"rms_um\" is not a key it has"},
        {"{" + ok + R"(,"readings":-1})", "\"readings\" must be a non-negative integer"},
        {R"({"converged":true,"residual_rms_um":0.1,"estimates":[{"name":"X0C","estimate":1}]})",
         "\"estimates[0].std\" is missing"},
        {R"({"converged":true,"residual_rms_um":0.1,"estimates":[{"name":"X0C","unit":"mm","value":1}]})",
         "\"estimates[0].value_std\" is missing"},
        {"{" + ok + R"(,"correlation":[[1,0]],"correlation_names":["X0C"]})", "\"correlation\" must be a square"},
        {"{" + ok + R"(,"model":{"params":{}}})", "\"model\" is not a model"},
    };
    for (const auto& c : cases) {
        try {
            (void)identification_from_json(c.text);
            ADD_FAILURE() << "accepted " << c.text;
        } catch (const FormatError& e) {
            EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << e.what();
        }
    }
}

}  // namespace
}  // namespace ballbar::storage
