// SPDX-License-Identifier: MIT
// Readings files: every number finite and within its column's documented range
// (docs/formats/readings.md, "Ranges"); a file outside is refused whole, naming the line and column.
#include <gtest/gtest.h>

#include <string>

#include "ballbar/storage/readings_file.hpp"

namespace ballbar::storage {
namespace {

struct Row {
    const char* name;
    const char* column;  ///< replaced in the valid row
    const char* value;
    const char* says;
};

void PrintTo(const Row& r, std::ostream* os) {
    *os << r.name;
}

const std::string kHead =
    "# ballbar-readings/1\n"
    "# machine: {\"type\":\"TTTRR\",\"a_pivot_mm\":[0,0,0],\"c_offset_mm\":[0,0,-100],\"tool_ball_mm\":[0,0,0]}\n";
const char* const kColumns[] = {"time_s",      "location",       "point",       "step",       "X_mm",
                                "Y_mm",        "Z_mm",           "A_deg",       "C_deg",      "socket_x_mm",
                                "socket_y_mm", "socket_z_mm",    "measured_mm", "nominal_mm", "bar_temp_C",
                                "air_temp_C",  "machine_temp_C", "n",           "std_mm"};
const char* const kValues[] = {"12.0",  "0",    "0",       "1",       "32.375",  "-14.312",  "-120.042",
                               "0",     "0",    "-49.275", "-14.312", "-77.777", "100.0021", "100",
                               "20.31", "20.1", "21",      "500",     "0.0003"};

/// The valid file with `column` set to `value` in its one row.
std::string file_with(const std::string& column, const std::string& value) {
    std::string head, row;
    for (std::size_t i = 0; i < std::size(kColumns); ++i) {
        head += (i ? "," : "") + std::string(kColumns[i]);
        row += (i ? "," : "") + (kColumns[i] == column ? value : std::string(kValues[i]));
    }
    return kHead + head + "\n" + row + "\n";
}

TEST(ReadingsRanges, TheValidRowIsAccepted) {
    const ReadingsFile f = parse_readings(file_with("", ""));
    ASSERT_EQ(f.set.readings.size(), 1u);
}

class OutOfRangeReading : public ::testing::TestWithParam<Row> {};

TEST_P(OutOfRangeReading, IsRefusedWithLineAndColumn) {
    const Row& r = GetParam();
    try {
        parse_readings(file_with(r.column, r.value));
        FAIL() << r.column << " = " << r.value << " was accepted";
    } catch (const ReadingsFileError& e) {
        EXPECT_EQ(e.line(), 4) << e.what();
        EXPECT_NE(std::string(e.what()).find(std::string("column \"") + r.column + "\""), std::string::npos)
            << e.what();
        EXPECT_NE(std::string(e.what()).find(r.says), std::string::npos) << e.what();
    }
}

INSTANTIATE_TEST_SUITE_P(
    Columns, OutOfRangeReading,
    ::testing::Values(
        Row{"X_1e308", "X_mm", "1e308", "= 1e+308 is outside [-100000, 100000] mm"},
        Row{"Y_minus_1e6", "Y_mm", "-1e6", "= -1000000 is outside"},
        Row{"A_deg_1e308", "A_deg", "1e308", "= 1e+308 is outside [-36000, 36000] deg"},
        Row{"C_deg_1e5", "C_deg", "1e5", "is outside"}, Row{"socket_1e308", "socket_z_mm", "1e308", "is outside"},
        Row{"measured_1e308", "measured_mm", "1e308", "must be > 0 and <= 10000 mm"},
        Row{"measured_zero", "measured_mm", "0", "= 0 must be > 0"},
        Row{"measured_negative", "measured_mm", "-100.0021", "must be > 0"},
        Row{"nominal_1e308", "nominal_mm", "1e308", "must be > 0"}, Row{"time_1e300", "time_s", "1e300", "is outside"},
        Row{"bar_temp_1e4", "bar_temp_C", "1e4", "is outside [-50, 150] C"},
        Row{"air_temp_below_absolute_zero", "air_temp_C", "-300", "is outside [-50, 150] C"},
        Row{"machine_temp_1e308", "machine_temp_C", "1e308", "is outside"},
        Row{"std_negative", "std_mm", "-0.001", "is outside [0, 10] mm"},
        Row{"std_1e308", "std_mm", "1e308", "is outside"}, Row{"x_infinity", "X_mm", "inf", "is not a finite number"},
        Row{"n_zero", "n", "0", "is not an integer"}),
    [](const auto& param_info) { return std::string(param_info.param.name); });

// Every coordinate in range, the bar they span not: found by fuzz_readings (CI, 2026-12-02), where such a
// file was accepted but refused when written back (the written nominal_mm column is out of range).
TEST(ReadingsRanges, APoseSpanningABarBeyondAnyBarIsRefused) {
    try {
        parse_readings(file_with("X_mm", "10050"));
        FAIL() << "a 10 m bar was accepted";
    } catch (const ReadingsFileError& e) {
        EXPECT_EQ(e.line(), 4);
        EXPECT_NE(std::string(e.what()).find("nominal bar length (from the pose and socket) = 10"), std::string::npos)
            << e.what();
        EXPECT_NE(std::string(e.what()).find("must be > 0 and <= 10000 mm"), std::string::npos) << e.what();
    }
}

TEST(ReadingsRanges, AMachineHeaderBeyondAnyMachineIsRefused) {
    std::string text = file_with("", "");
    text.replace(text.find("\"tool_ball_mm\":[0,0,0]"), 22, "\"tool_ball_mm\":[0,0,1e308]");
    try {
        parse_readings(text);
        FAIL();
    } catch (const ReadingsFileError& e) {
        EXPECT_EQ(e.line(), 2);
        EXPECT_NE(std::string(e.what()).find("machine.tool_ball_mm[2] = 1e+308 is outside"), std::string::npos)
            << e.what();
    }
}

}  // namespace
}  // namespace ballbar::storage
