// SPDX-License-Identifier: MIT
// ballbar-trace/1: the specification's example, every invalid file of the corpus refused with its line
// and problem, lossless write → parse, and a trace stored as a session and loaded back.
#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "accuracy.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/storage/trace_file.hpp"

namespace {

using namespace ballbar::storage;
const std::string kDir = std::string(BALLBAR_TEST_DATA_DIR) + "/traces/";

TEST(TraceFile, ParsesTheExampleWithCrlfCommentsTemperaturesAndUnknownKeys) {
    const TraceFile t = read_trace_file(kDir + "spec_example.csv");
    EXPECT_EQ(t.test.plane, ballbar::analysis::circular::Plane::XY);
    EXPECT_DOUBLE_EQ(t.test.radius_mm, 100.0);
    ASSERT_EQ(t.test.runs.size(), 2u);
    EXPECT_EQ(t.test.runs[1].direction, ballbar::analysis::circular::Direction::Cw);
    EXPECT_DOUBLE_EQ(t.test.runs[1].start_deg, 90.0);
    ASSERT_EQ(t.samples.size(), 3u);
    EXPECT_DOUBLE_EQ(t.samples[2].measured_mm, 101.4999);
    ASSERT_EQ(t.bar_temp_C.size(), 3u);
    EXPECT_FALSE(t.bar_temp_C[2].has_value());
    EXPECT_FALSE(t.air_temp_C[1].has_value());
    EXPECT_EQ(t.operator_name, "J. Smith");
    ASSERT_EQ(t.extra.size(), 1u);
    EXPECT_EQ(t.extra[0].first, "site");
    ASSERT_EQ(t.warnings.size(), 1u);
    EXPECT_NE(t.warnings[0].find("extra_col"), std::string::npos);
}

struct Invalid {
    const char* file;
    int line;
    const char* problem;
};

class InvalidTraceFile : public ::testing::TestWithParam<Invalid> {};

TEST_P(InvalidTraceFile, IsRefusedWithLineAndProblem) {
    const Invalid& c = GetParam();
    try {
        read_trace_file(kDir + "invalid/" + c.file);
        FAIL() << c.file << " was accepted";
    } catch (const TraceFileError& e) {
        EXPECT_EQ(e.line(), c.line) << e.what();
        EXPECT_NE(std::string(e.what()).find(c.problem), std::string::npos) << e.what();
    }
}

INSTANTIATE_TEST_SUITE_P(
    Files, InvalidTraceFile,
    ::testing::Values(Invalid{"empty.csv", 1, "empty file"}, Invalid{"bad_magic.csv", 1, "unsupported format version"},
                      Invalid{"not_trace.csv", 1, "not a ballbar-trace/1 file"},
                      Invalid{"no_test.csv", 3, "no \"# test"}, Invalid{"bad_test_json.csv", 2, "not one line of JSON"},
                      Invalid{"bad_plane.csv", 2, "is not XY, YZ or ZX"}, Invalid{"bad_kind.csv", 2, "\"kind\""},
                      Invalid{"missing_radius.csv", 2, "needs \"radius_mm\""},
                      Invalid{"negative_feed.csv", 2, "feed_mm_min = -5 is outside [0.1, 200000] mm/min"},
                      Invalid{"feed_1e308.csv", 2, "feed_mm_min = 1e+308 is outside"},
                      Invalid{"feed_1e_minus_300.csv", 2, "feed_mm_min = 1e-300 is outside"},
                      Invalid{"radius_1e308.csv", 2, "radius_mm = 1e+308 must be > 0 and <= 10000 mm"},
                      Invalid{"centre_1e308.csv", 2, "centre_mm[1] = 1e+308 is outside"},
                      Invalid{"start_1e308.csv", 2, "runs[0]: start_deg = 1e+308 is outside"},
                      Invalid{"unknown_test_key.csv", 2, "test: unknown key \"overshot_deg\""},
                      Invalid{"unknown_run_key.csv", 2, "runs[0]: unknown key \"speed\""},
                      Invalid{"time_1e308.csv", 5, "time_s = 1e+308 is outside"},
                      Invalid{"measured_1e308.csv", 4, "measured_mm = 1e+308 must be > 0 and <= 10000 mm"},
                      Invalid{"temperature_1e308.csv", 5, "bar_temp_C = 1e+308 is outside [-50, 150] C"},
                      Invalid{"bad_direction.csv", 2, "is not ccw or cw"}, Invalid{"no_runs.csv", 2, "\"runs\""},
                      Invalid{"duplicate_header.csv", 3, "duplicate header \"test\""},
                      Invalid{"operator_not_string.csv", 3, "must be a JSON string"},
                      Invalid{"missing_column.csv", 3, "missing column \"measured_mm\""},
                      Invalid{"duplicate_column.csv", 3, "appears twice"}, Invalid{"no_rows.csv", 3, "no data rows"},
                      Invalid{"non_numeric.csv", 5, "is not a number"}, Invalid{"nan_value.csv", 5, "is not a number"},
                      Invalid{"time_not_increasing.csv", 6, "strictly increase"},
                      Invalid{"wrong_field_count.csv", 5, "3 fields where the column row has 2"},
                      Invalid{"negative_measured.csv", 4, "must be > 0"},
                      Invalid{"header_after_columns.csv", 5, "header line after the column row"},
                      Invalid{"bad_temperature.csv", 4, "bar_temp_C \"warm\""}),
    [](const auto& param_info) {
        std::string name = param_info.param.file;
        return name.substr(0, name.find('.'));
    });

TEST(TraceFile, WriteThenParseIsLossless) {
    std::mt19937_64 rng(11);
    auto c = ballbar::testgen::random_case(rng);
    c.spec.radius_mm = 50.0, c.spec.feed_mm_min = 2000.0, c.spec.sample_hz = 300.0;
    const auto g = ballbar::testgen::generate(c.spec, c.fx, rng);
    const TraceFile a = parse_trace(ballbar::testgen::to_file(c.spec, g));
    const TraceFile b = parse_trace(format_trace(a));
    ASSERT_EQ(a.samples.size(), b.samples.size());
    for (std::size_t i = 0; i < a.samples.size(); ++i) {
        ASSERT_EQ(a.samples[i].time_s, b.samples[i].time_s);
        ASSERT_EQ(a.samples[i].measured_mm, b.samples[i].measured_mm);
    }
    EXPECT_EQ(test_json(a.test), test_json(b.test));
    EXPECT_EQ(a.instrument_json, b.instrument_json);
}

TEST(TraceFile, StoredAsASessionAndLoadedBack) {
    const auto dir = std::filesystem::temp_directory_path() / ("ballbar_trace_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    {
        Store store((dir / "t.db").string());
        const TraceFile t = read_trace_file(kDir + "spec_example.csv");
        const auto id = import_trace(store, t, "spec_example.csv");
        EXPECT_EQ(store.session(id).procedure, "circular");
        EXPECT_EQ(store.sample_count(id), 3);
        const TraceFile back = load_trace(store, id);
        EXPECT_EQ(test_json(back.test), test_json(t.test));
        ASSERT_EQ(back.samples.size(), 3u);
        EXPECT_NEAR(back.samples[2].measured_mm, 101.4999, 1e-9);
        EXPECT_NEAR(back.samples[1].time_s, 0.001, 1e-12);
        EXPECT_EQ(back.operator_name, "J. Smith");
    }
    std::filesystem::remove_all(dir);
}

/// Issue 24: export → import → export was not a fixed point (100.7889 came back as
/// 100.78890000000001, so a re-import was not recognised as the same file).
TEST(TraceFile, StoredAndLoadedBackWritesTheSameText) {
    const auto dir = std::filesystem::temp_directory_path() / ("ballbar_trace_fp_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    {
        TraceFile t = read_trace_file(kDir + "spec_example.csv");
        t.samples.clear();
        t.bar_temp_C.clear();
        t.air_temp_C.clear();
        for (int i = 0; i < 2000; ++i)  // 1 kHz; lengths on a 0.1 µm grid around 100.75 mm
            t.samples.push_back(
                {static_cast<double>(10 * i + 3) / 1e4, static_cast<double>(1007889 + (i % 37) - 19 * (i % 11)) / 1e4});
        const std::string first = format_trace(t);
        Store store((dir / "t.db").string());
        const std::string second = format_trace(load_trace(store, import_trace(store, parse_trace(first), "a.csv")));
        const std::string third = format_trace(load_trace(store, import_trace(store, parse_trace(second), "b.csv")));
        EXPECT_EQ(second.find("00000000"), std::string::npos) << "no binary noise in the text";
        EXPECT_EQ(second.substr(second.find("time_s")), first.substr(first.find("time_s")));
        EXPECT_EQ(third, second);
    }
    std::filesystem::remove_all(dir);
}

}  // namespace
