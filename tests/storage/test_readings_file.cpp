// SPDX-License-Identifier: MIT
// The `ballbar-readings/1` reader and writer: valid files of all three machine types, every kind of
// invalid file (refused with its line and problem), and lossless parse → write → parse.
#include <gtest/gtest.h>

#include <cmath>

#include "ballbar/analysis/kinematics.hpp"
#include "ballbar/storage/readings.hpp"
#include "ballbar/storage/readings_file.hpp"
#include "test_util.hpp"

namespace ballbar::storage {
namespace {

const std::string kDirReadingsFile = std::string(BALLBAR_TEST_DATA_DIR) + "/readings/";

void expect_same(const analysis::ReadingSet& a, const analysis::ReadingSet& b) {
    EXPECT_EQ(a.machine.type, b.machine.type);
    EXPECT_EQ(a.machine.name, b.machine.name);
    EXPECT_EQ(a.machine.tool_ball_mm, b.machine.tool_ball_mm);
    EXPECT_EQ(a.machine.a_pivot_mm, b.machine.a_pivot_mm);
    EXPECT_EQ(a.machine.c_offset_mm, b.machine.c_offset_mm);
    ASSERT_EQ(a.readings.size(), b.readings.size());
    for (std::size_t i = 0; i < a.readings.size(); ++i) {
        const auto& x = a.readings[i];
        const auto& y = b.readings[i];
        SCOPED_TRACE("reading " + std::to_string(i));
        EXPECT_EQ(x.pose.X_mm, y.pose.X_mm);
        EXPECT_EQ(x.pose.Y_mm, y.pose.Y_mm);
        EXPECT_EQ(x.pose.Z_mm, y.pose.Z_mm);
        EXPECT_EQ(x.pose.A_rad, y.pose.A_rad);
        EXPECT_EQ(x.pose.B_rad, y.pose.B_rad);
        EXPECT_EQ(x.pose.C_rad, y.pose.C_rad);
        EXPECT_EQ(x.socket_mm, y.socket_mm);
        EXPECT_EQ(x.measured_mm, y.measured_mm);
        EXPECT_EQ(x.time_s, y.time_s);
        EXPECT_EQ(x.bar_temp_C, y.bar_temp_C);
        EXPECT_EQ(x.air_temp_C, y.air_temp_C);
        EXPECT_EQ(x.machine_temp_C, y.machine_temp_C);
        EXPECT_EQ(x.location, y.location);
        EXPECT_EQ(x.point, y.point);
        EXPECT_EQ(x.step, y.step);
        EXPECT_EQ(x.n, y.n);
        EXPECT_EQ(x.std_mm, y.std_mm);
    }
}

TEST(ReadingsFile, ParsesTheSpecExample) {
    const auto f = read_readings_file(kDirReadingsFile + "spec_example.csv");
    EXPECT_EQ(f.set.machine.type, analysis::MachineType::TTTRR);
    EXPECT_EQ(f.set.machine.c_offset_mm, analysis::Vec3(0, 0, -100));
    ASSERT_EQ(f.set.readings.size(), 1u);
    const auto& r = f.set.readings[0];
    EXPECT_EQ(r.pose.X_mm, 32.375);
    EXPECT_EQ(r.pose.C_rad, 0);
    EXPECT_EQ(r.socket_mm.z(), -77.777);
    EXPECT_EQ(r.measured_mm, 100.0021);
    EXPECT_EQ(r.time_s, 12.0);
    EXPECT_EQ(r.bar_temp_C, 20.31);
    EXPECT_EQ(r.location, 0);
    EXPECT_EQ(r.point, 0);
    EXPECT_EQ(r.step, 0);
    ASSERT_TRUE(f.metadata.instrument);
    EXPECT_EQ(f.metadata.instrument->serial, "0042");
    EXPECT_EQ(f.metadata.instrument->calibrated_length_mm, 100.0);
    EXPECT_NEAR(f.nominal_mm[0], std::sqrt(81.65 * 81.65 + 57.735 * 57.735), 1e-9);
    EXPECT_TRUE(f.warnings.empty());
}

TEST(ReadingsFile, ColumnsByNameInAnyOrderWithQuotesCrlfAndUnknownColumnsWarnedOnce) {
    const auto f = read_readings_file(kDirReadingsFile + "tttrr_full_crlf.csv");
    ASSERT_EQ(f.set.readings.size(), 8u);
    const auto& r = f.set.readings[5];
    EXPECT_EQ(r.location, 1);
    EXPECT_EQ(r.point, 1);
    EXPECT_EQ(r.step, 1);
    EXPECT_EQ(r.n, 250);
    EXPECT_EQ(r.std_mm, 0.00015);
    EXPECT_EQ(r.air_temp_C, 21.0);
    EXPECT_EQ(r.machine_temp_C, 22.5);
    EXPECT_DOUBLE_EQ(r.pose.A_rad, analysis::deg_to_rad(-30));
    EXPECT_DOUBLE_EQ(r.pose.C_rad, analysis::deg_to_rad(90));
    ASSERT_EQ(f.warnings.size(), 1u);
    EXPECT_NE(f.warnings[0].find("\"comment\", \"spindle_load\""), std::string::npos) << f.warnings[0];
    EXPECT_NE(f.warnings[0].find("line 10"), std::string::npos) << f.warnings[0];
    EXPECT_EQ(f.metadata.operator_name, "Ada Lovelace");
    EXPECT_EQ(f.metadata.started_at, "2026-11-20T09:15:00Z");
    EXPECT_EQ(f.metadata.notes, "warm machine, \"quoted\" notes");
    ASSERT_EQ(f.metadata.extra.size(), 1u);
    EXPECT_EQ(f.metadata.extra[0].first, "shop_order");
    ASSERT_TRUE(f.metadata.instrument);
    EXPECT_EQ(f.metadata.instrument->firmware, "2.1");
    EXPECT_EQ(f.metadata.instrument->extra_json, R"({"lab":"Metrology 3"})");
    EXPECT_TRUE(f.nominal_mismatches.empty()) << "the file's nominal lengths follow the spec's conventions";
}

TEST(ReadingsFile, RecomputesNominalForAllTypesAndReportsDisagreement) {
    const auto rr = read_readings_file(kDirReadingsFile + "rrttt_minimal.csv");
    EXPECT_EQ(rr.set.machine.type, analysis::MachineType::RRTTT);
    EXPECT_EQ(rr.set.readings.size(), 5u);
    EXPECT_TRUE(rr.nominal_mismatches.empty());
    EXPECT_DOUBLE_EQ(rr.set.readings[2].pose.B_rad, analysis::deg_to_rad(30));

    const auto rt = read_readings_file(kDirReadingsFile + "rtttr_nominal_mismatch.csv");
    EXPECT_EQ(rt.set.machine.type, analysis::MachineType::RTTTR);
    ASSERT_EQ(rt.nominal_mismatches.size(), 1u);
    EXPECT_EQ(rt.nominal_mismatches[0].line, 5);
    EXPECT_EQ(rt.nominal_mismatches[0].row, 1u);
    EXPECT_NEAR(rt.nominal_mismatches[0].file_nominal_mm - rt.nominal_mismatches[0].computed_nominal_mm, 0.01, 1e-9);
}

struct Invalid {
    const char* file;
    int line;
    const char* problem;
};

class InvalidReadingsFile : public ::testing::TestWithParam<Invalid> {};

TEST_P(InvalidReadingsFile, IsRefusedWithLineAndProblem) {
    const Invalid& c = GetParam();
    try {
        read_readings_file(kDirReadingsFile + "invalid/" + c.file);
        FAIL() << c.file << " was accepted";
    } catch (const ReadingsFileError& e) {
        EXPECT_EQ(e.line(), c.line) << e.what();
        EXPECT_NE(std::string(e.what()).find(c.problem), std::string::npos) << e.what();
        EXPECT_EQ(std::string(e.what()).rfind("line " + std::to_string(c.line) + ": ", 0), 0u) << e.what();
    }
}

INSTANTIATE_TEST_SUITE_P(
    Files, InvalidReadingsFile,
    ::testing::Values(Invalid{"empty.csv", 1, "empty file"}, Invalid{"bad_magic.csv", 1, "unsupported format version"},
                      Invalid{"not_readings.csv", 1, "not a readings file"},
                      Invalid{"no_machine.csv", 3, "no \"# machine"},
                      Invalid{"bad_machine_json.csv", 2, "not one line of JSON"},
                      Invalid{"bad_machine_type.csv", 2, "\"TRTRT\" is not RRTTT, TTTRR or RTTTR"},
                      Invalid{"missing_geometry.csv", 2, "needs \"c_offset_mm\""},
                      Invalid{"bad_geometry_shape.csv", 2, "machine.tool_ball_mm must be an array of 3 numbers"},
                      Invalid{"missing_column.csv", 3, "required column \"measured_mm\" is missing"},
                      Invalid{"wrong_rotary_column.csv", 3, "required column \"C_deg\" is missing"},
                      Invalid{"duplicate_column.csv", 3, "column \"X_mm\" appears twice"},
                      Invalid{"non_numeric.csv", 5, "\"-12O.042\" is not a finite number"},
                      Invalid{"nan_value.csv", 4, "\"nan\" is not a finite number"},
                      Invalid{"wrong_field_count.csv", 6, "10 fields, but the column row has 9"},
                      Invalid{"unclosed_quote.csv", 5, "quoted field is not closed"},
                      Invalid{"bad_step.csv", 5, "column \"step\": 3 is not an integer in [1, 2]"},
                      Invalid{"fractional_location.csv", 4, "\"location\": 1.5 is not an integer"},
                      Invalid{"negative_measured.csv", 4, "column \"measured_mm\" = -100.0021 must be > 0"},
                      Invalid{"empty_required.csv", 4, "column \"Z_mm\" is empty"},
                      Invalid{"no_rows.csv", 4, "no readings"},
                      Invalid{"header_after_columns.csv", 5, "header line after the column row"},
                      Invalid{"duplicate_header.csv", 3, "\"machine\" given twice (first on line 2)"},
                      Invalid{"bad_started_at.csv", 3, "not an ISO 8601 time"},
                      Invalid{"operator_not_string.csv", 3, "operator must be a JSON string"},
                      Invalid{"bad_instrument.csv", 3, "calibrated_length_mm must be a positive number"},
                      Invalid{"stray_quote.csv", 4, "a quote inside an unquoted field"}),
    [](const auto& param_info) {
        std::string name = param_info.param.file;
        return name.substr(0, name.find('.'));
    });

TEST(ReadingsFile, MissingFileIsLineZero) {
    try {
        read_readings_file(kDirReadingsFile + "does-not-exist.csv");
        FAIL();
    } catch (const ReadingsFileError& e) {
        EXPECT_EQ(e.line(), 0);
        EXPECT_NE(std::string(e.what()).find("no such readings file"), std::string::npos) << e.what();
    }
}

TEST(ReadingsFile, ParseWriteParseIsLossless) {
    for (const char* name :
         {"spec_example.csv", "tttrr_full_crlf.csv", "rrttt_minimal.csv", "rtttr_nominal_mismatch.csv"}) {
        SCOPED_TRACE(name);
        const auto a = read_readings_file(kDirReadingsFile + name);
        const std::string text = format_readings(a.set, a.metadata);
        const auto b = parse_readings(text);
        expect_same(a.set, b.set);
        EXPECT_EQ(b.metadata.operator_name, a.metadata.operator_name);
        EXPECT_EQ(b.metadata.notes, a.metadata.notes);
        EXPECT_EQ(b.metadata.started_at, a.metadata.started_at);
        EXPECT_EQ(b.metadata.extra, a.metadata.extra);
        EXPECT_EQ(b.metadata.instrument.has_value(), a.metadata.instrument.has_value());
        EXPECT_TRUE(b.nominal_mismatches.empty()) << "the writer writes the recomputed nominal length";
        EXPECT_EQ(format_readings(b.set, b.metadata), text) << "writing is a fixed point";
    }
}

TEST(ReadingsFile, WriterKeepsArbitraryRadiansExact) {
    analysis::ReadingSet set;
    set.machine = test::tttrr();
    for (int i = 0; i < 500; ++i) {
        analysis::Reading r;
        r.pose = {i * 0.1234567, -i * 0.7, 3.0, std::sin(i) * 1.7, 0, std::cos(i * 0.37) * 3.1};
        r.socket_mm = {80, 0.1 * i, 20};
        r.measured_mm = 100 + i * 1e-7;
        set.readings.push_back(r);
    }
    const auto back = parse_readings(format_readings(set));
    // Not every radian value has a decimal degree that maps back to it exactly (doubles in degrees are
    // ~57 times sparser); the writer then picks the nearest one: within a couple of ulps.
    for (std::size_t i = 0; i < set.readings.size(); ++i) {
        const auto& a = set.readings[i].pose;
        const auto& b = back.set.readings[i].pose;
        EXPECT_NEAR(b.A_rad, a.A_rad, 4.5e-16 * std::max(1.0, std::abs(a.A_rad)));
        EXPECT_NEAR(b.C_rad, a.C_rad, 4.5e-16 * std::max(1.0, std::abs(a.C_rad)));
        EXPECT_EQ(back.set.readings[i].pose.X_mm, a.X_mm);
        EXPECT_EQ(back.set.readings[i].measured_mm, set.readings[i].measured_mm);
    }
    // Radians that came from degrees (every imported file) come back exactly.
    for (int i = -3600; i <= 3600; i += 7) {
        const double rad = analysis::deg_to_rad(i * 0.1);
        set.readings[0].pose.A_rad = rad;
        EXPECT_EQ(parse_readings(format_readings(set)).set.readings[0].pose.A_rad, rad) << i * 0.1;
    }
}

TEST(ReadingsFile, WritesTheShortestDegreesAndParsesMultiLineQuotedFields) {
    const auto f = read_readings_file(kDirReadingsFile + "tttrr_full_crlf.csv");
    const std::string text = format_readings(f.set, f.metadata);
    EXPECT_NE(text.find(",-30,90,"), std::string::npos) << text;
    EXPECT_EQ(text.find("29.99999"), std::string::npos) << text;
    EXPECT_NE(text.find("# machine: {\"type\":\"TTTRR\",\"name\":\"DL-5X\""), std::string::npos) << text;

    const auto g = parse_readings(
        "# ballbar-readings/1\n"
        "# machine: {\"type\":\"RRTTT\",\"tool_ball_mm\":[0,0,-150]}\n"
        "X_mm,Y_mm,Z_mm,A_deg,B_deg,socket_x_mm,socket_y_mm,socket_z_mm,measured_mm,remark\n"
        "1,2,3,0,0,4,5,6,150.1,\"two\nlines, \"\"quoted\"\"\"\n"
        " \"7\" ,2,3,0,0,4,5,6,150.2,x\n");
    ASSERT_EQ(g.set.readings.size(), 2u);
    EXPECT_EQ(g.set.readings[1].pose.X_mm, 7);
    EXPECT_EQ(g.set.readings[1].measured_mm, 150.2);
}

TEST(ReadingsFile, ImportIsOneTransactionAndLoadReadingsReturnsIt) {
    test::TempDir dir;
    Store store(dir.file("a.db"));
    const auto f = read_readings_file(kDirReadingsFile + "tttrr_full_crlf.csv");
    const auto id = import_readings(store, f, "tttrr_full_crlf.csv");
    const auto info = store.session(id);
    EXPECT_EQ(info.source, SessionSource::imported);
    EXPECT_EQ(info.state, SessionState::completed);
    EXPECT_EQ(info.started_at, "2026-11-20T09:15:00Z");
    EXPECT_EQ(info.point_count, 8);
    expect_same(load_readings(store, id), f.set);
    const auto meta = readings_metadata(info);
    EXPECT_EQ(meta.extra, f.metadata.extra);
    EXPECT_EQ(store.transitions(id).back().event, "import: tttrr_full_crlf.csv");

    // A failure in the middle leaves nothing behind.
    auto bad = f;
    bad.set.readings[4].measured_mm = std::nan("");  // violates NOT NULL (NaN binds as NULL)
    EXPECT_THROW(import_readings(store, bad), StorageError);
    EXPECT_EQ(store.sessions().size(), 1u);
    EXPECT_EQ(store.db().query_int("SELECT count(*) FROM points"), 8);
}

}  // namespace
}  // namespace ballbar::storage
