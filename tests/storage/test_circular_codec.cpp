// SPDX-License-Identifier: MIT
// The stored circular result's reader (storage/circular_result.hpp): a payload in docs/cli.md's
// vocabulary, written here by hand from docs/report.md's list of keys, read into the typed record; one
// stored before the vocabulary (maps and a ranking) read into the same record; a malformed one refused
// naming the key.
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "ballbar/storage/circular_result.hpp"
#include "ballbar/storage/machine_json.hpp"

namespace ballbar::storage {
namespace {

const std::string kTest = R"("test": {"kind": "circular", "plane": "XY", "radius_mm": 100, "centre_mm": [1, 2, 3],
    "feed_mm_min": 1000, "feed_in_mm": 0.8, "runs": [{"direction": "ccw", "start_deg": 0, "overshoot_deg": 45,
    "data_arc_deg": 360}, {"direction": "cw", "start_deg": 450, "overshoot_deg": 45, "data_arc_deg": 360}]},
  "runs": [{"direction": "ccw", "circularity_um": 6.5, "radial_deviation_um": {"max": 3.5, "min": -3.0},
            "feed_in_end_s": 1.0, "feed_in_lag_ms": 8.0, "data_start_s": 2.0, "data_end_s": 40.0, "samples": 3800},
           {"direction": "cw", "circularity_um": 7.0, "radial_deviation_um": {"max": 3.0, "min": -4.0}}])";

TEST(CircularCodec, AResultInTheVocabularyIsReadTyped) {
    const CircularRecord c = circular_result_from_json("{" + kTest + R"(,
      "bidirectional_circularity_um": 9.5, "radial_deviation_um": {"max": 3.5, "min": -4.0},
      "diagnostics": [{"key": "backlash_x_um", "unit": "um", "value": 3.1, "value_std": 0.05, "share_percent": 55, "rank": 1},
                      {"key": "cyclic_pitch_x_mm", "unit": "mm", "value": 6.0, "value_std": 0.01, "share_percent": null, "rank": null}],
      "not_detected": ["vibration_um"], "unseparable": [],
      "residual_rms_um": 0.2, "mean_radius_um": 1.5, "mean_radius_um_std": 0.02,
      "conditions": {"sample_rate_hz": 100, "samples_used": 7600, "bar_temp_C": {"min": 20.0, "max": 20.5},
                     "air_temp_C": null, "instrument": {"serial": "B1"}},
      "tolerance": {"circularity_um": 10, "pass": true}})");
    EXPECT_EQ(c.plane, "XY");
    EXPECT_DOUBLE_EQ(c.centre_mm[2], 3);
    ASSERT_EQ(c.runs.size(), 2u);
    EXPECT_DOUBLE_EQ(c.runs[1].start_deg, 450);
    EXPECT_DOUBLE_EQ(*c.runs[0].samples, 3800);
    EXPECT_FALSE(c.runs[1].samples.has_value());
    EXPECT_DOUBLE_EQ(*c.bidirectional_um, 9.5);
    ASSERT_EQ(c.diagnostics.size(), 2u);
    EXPECT_EQ(c.diagnostics[0].rank, 1);
    EXPECT_FALSE(c.diagnostics[1].rank.has_value());
    EXPECT_DOUBLE_EQ(*c.diagnostics[0].value_std, 0.05);
    EXPECT_EQ(c.not_detected, std::vector<std::string>{"vibration_um"});
    EXPECT_DOUBLE_EQ(*c.mean_radius_um_std, 0.02);
    EXPECT_DOUBLE_EQ(*c.bar_temp_max_C, 20.5);
    EXPECT_FALSE(c.air_temp_min_C.has_value());
    EXPECT_EQ(c.instrument, R"({"serial":"B1"})");
    EXPECT_DOUBLE_EQ(*c.tolerance_um, 10);
    EXPECT_TRUE(c.runs[0].model_arc_deg.empty()) << "a result without a model curve has none";
}

TEST(CircularCodec, TheModelCurveIsReadPerRun) {
    std::string text = "{" + kTest + "}";
    text.replace(text.find("\"samples\": 3800"), 15,
                 R"("samples": 3800, "model_curve": {"arc_deg": [0.1, 0.4, 0.6], "deviation_um": [1.5, -2.25, 0]})");
    const CircularRecord c = circular_result_from_json(text);
    EXPECT_EQ(c.runs[0].model_arc_deg, (std::vector<double>{0.1, 0.4, 0.6}));
    EXPECT_EQ(c.runs[0].model_deviation_um, (std::vector<double>{1.5, -2.25, 0}));
    EXPECT_TRUE(c.runs[1].model_deviation_um.empty());
}

TEST(CircularCodec, AResultStoredBeforeTheVocabularyIsReadIntoTheSameRecord) {
    const CircularRecord c = circular_result_from_json("{" + kTest + R"(,
      "diagnostics": {"backlash_x_um": 3.1, "scale_mismatch_ppm": 12, "vibration_hz": 30},
      "uncertainties": {"backlash_x_um": 0.05, "scale_mismatch_ppm": 0.4},
      "shares_percent": {"backlash_x_um": 40, "scale_mismatch_ppm": 60},
      "ranking": ["scale_mismatch_ppm", "backlash_x_um"],
      "unseparable": [{"keys": ["a", "b"], "reason": "partial arc", "combined": {"as": "a+b", "value": 1, "std_uncertainty": 0.1}}],
      "mean_radius_um": {"value": 1.5, "std_uncertainty": 0.01}})");
    ASSERT_EQ(c.diagnostics.size(), 3u);
    for (const auto& d : c.diagnostics) {
        const std::optional<int> expected_rank = d.key == "scale_mismatch_ppm" ? std::optional<int>(1)
                                                 : d.key == "backlash_x_um"    ? std::optional<int>(2)
                                                                               : std::nullopt;
        EXPECT_EQ(d.rank, expected_rank) << d.key;
    }
    for (const auto& d : c.diagnostics) {
        if (d.key != "backlash_x_um") continue;
        EXPECT_DOUBLE_EQ(*d.share_percent, 40);
    }
    ASSERT_EQ(c.unseparable.size(), 1u);
    EXPECT_EQ(c.unseparable[0].combined_key, "a+b");
    EXPECT_DOUBLE_EQ(*c.unseparable[0].combined_value_std, 0.1);
    EXPECT_DOUBLE_EQ(*c.mean_radius_um, 1.5);
    EXPECT_DOUBLE_EQ(*c.mean_radius_um_std, 0.01);
}

TEST(CircularCodec, AMalformedResultIsRefusedNamingTheKey) {
    std::string bad = "{" + kTest + "}";
    bad.replace(bad.find("\"circularity_um\": 7.0"), 21, "\"circularity_um\": \"x\"");
    try {
        circular_result_from_json(bad);
        FAIL() << "read";
    } catch (const FormatError& e) {
        EXPECT_NE(std::string(e.what()).find("runs[1].circularity_um"), std::string::npos) << e.what();
    }
    // The model curve: two arrays of numbers, as long as each other.
    for (const auto& [curve, key] : std::vector<std::pair<std::string, std::string>>{
             {R"("model_curve": {"arc_deg": [0, 0.5], "deviation_um": [1]})", "runs[0].model_curve.deviation_um"},
             {R"("model_curve": {"arc_deg": [0, "x"], "deviation_um": [1, 2]})", "runs[0].model_curve.arc_deg"},
             {R"("model_curve": [1, 2])", "runs[0].model_curve.arc_deg"}}) {
        std::string m = "{" + kTest + "}";
        m.replace(m.find("\"samples\": 3800"), 15, "\"samples\": 3800, " + curve);
        try {
            circular_result_from_json(m);
            ADD_FAILURE() << "read " << curve;
        } catch (const FormatError& e) {
            EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
        }
    }
    EXPECT_THROW(circular_result_from_json("[1]"), FormatError);
    EXPECT_THROW(circular_result_from_json("{\"runs\": []}"), FormatError);
}

}  // namespace
}  // namespace ballbar::storage
