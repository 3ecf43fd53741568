// SPDX-License-Identifier: MIT
// The stored discovery result (storage/discovery_codec.hpp): what the writer stores of a real discovery
// run reads back into the typed record (the steps, the figures, each step's trend, the model made); a
// result stored before docs/cli.md's vocabulary (estimate/stderr, RMS in mm) reads into the same record;
// a malformed one is refused naming the key.
#include <gtest/gtest.h>

#include <string>

#include "ballbar/analysis/discovery.hpp"
#include "ballbar/storage/discovery_codec.hpp"
#include "ballbar/storage/machine_json.hpp"
#include "ballbar/storage/readings_file.hpp"

namespace ballbar::storage {
namespace {

TEST(DiscoveryCodec, WhatIsStoredOfARunReadsBack) {
    const ReadingsFile file =
        read_readings_file(std::string(BALLBAR_TEST_DATA_DIR) + "/readings/discovery_spindle_growth.csv");
    const analysis::DiscoveryResult result = analysis::discover(file.set);
    ASSERT_FALSE(result.steps.empty() && result.learned.empty()) << "the file has an effect to find";
    const DiscoveryRecord r =
        discovery_from_json(discovery_to_json(result, DiscoveryStored{{"growth.csv"}, "DL-5X-discovered", 7, 3}));
    EXPECT_EQ(r.steps.size(), result.steps.size() + result.learned.size());
    EXPECT_NEAR(*r.rms_initial_um, result.rms_initial_mm * 1e3, 1e-9);
    EXPECT_NEAR(*r.rms_final_um, result.rms_final_mm * 1e3, 1e-9);
    EXPECT_EQ(r.step_trends.size(), r.steps.size());
    for (std::size_t i = 0; i < result.steps.size(); ++i) {
        EXPECT_EQ(r.steps[i].kind, "library");
        EXPECT_EQ(r.steps[i].effect, std::string(result.steps[i].effect->id));
        EXPECT_NEAR(*r.steps[i].value, result.steps[i].estimate, 1e-15);
        EXPECT_NEAR(*r.steps[i].rms_after_um, result.steps[i].rms_after_mm * 1e3, 1e-9);
    }
    EXPECT_FALSE(r.residuals_initial.empty());
    EXPECT_EQ(r.model_name, "DL-5X-discovered");
    EXPECT_EQ(r.model_version, 3);
    ASSERT_TRUE(r.verdict.has_value());
    // What `discover --json` prints is the same result without the details and the model.
    const DiscoveryRecord printed = discovery_from_json(discovery_to_json(result));
    EXPECT_EQ(printed.steps.size(), r.steps.size());
    EXPECT_TRUE(printed.step_trends.empty());
    EXPECT_TRUE(printed.model_name.empty());
}

TEST(DiscoveryCodec, AResultStoredBeforeTheVocabularyReadsIntoTheSameRecord) {
    const DiscoveryRecord r = discovery_from_json(R"({"steps": [
        {"effect": "spindle_growth", "iso": "EZS", "unit": "mm_per_h", "estimate": 0.004, "stderr": 0.0002,
         "rms_before_mm": 0.003, "rms_after_mm": 0.0004, "explained_by": "time"}],
        "rms_initial_um": 3.0, "rms_final_um": 0.4, "noise_source": null})");
    ASSERT_EQ(r.steps.size(), 1u);
    EXPECT_DOUBLE_EQ(*r.steps[0].value, 0.004);
    EXPECT_DOUBLE_EQ(*r.steps[0].value_std, 0.0002);
    EXPECT_DOUBLE_EQ(*r.steps[0].rms_before_um, 3.0);
    EXPECT_FALSE(r.steps[0].accepted.has_value());
    EXPECT_FALSE(r.noise_source.has_value());
}

TEST(DiscoveryCodec, AMalformedResultIsRefusedNamingTheKey) {
    for (const auto& [text, key] : {std::pair<std::string, std::string>{R"({"rms_initial_um": 1})", "steps"},
                                    {R"({"steps": [{"value": "big"}]})", "value"},
                                    {R"({"steps": [{"x": [1, 2], "before_mm": [1], "after_mm": [1, 2]}]})", "x"}}) {
        try {
            discovery_from_json(text);
            ADD_FAILURE() << text;
        } catch (const FormatError& e) {
            EXPECT_NE(std::string(e.what()).find("\"" + key + "\""), std::string::npos) << e.what();
        }
    }
    EXPECT_THROW(discovery_from_json("not json"), FormatError);
}

}  // namespace
}  // namespace ballbar::storage
