// SPDX-License-Identifier: MIT
// What the fuzzers found in the commands' own input handling (docs/fuzzing.md), each kept as a test.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_harness.hpp"

namespace {

using ballbar::test::run;
using ballbar::test::TempDir;

// fuzz_cli_json: a request that is not UTF-8 was refused with the parse error quoting its bytes, and
// writing that error as JSON threw ("[json.exception.type_error.316] invalid UTF-8 byte", exit 1). The
// refusal is JSON on stderr with the bytes replaced, exit 2.
TEST(CliFuzzFindings, ARequestThatIsNotUtf8IsRefusedAsMalformedJson) {
    TempDir dir;
    for (const char* solver : {"ssm", "orientation", "compensate"}) {
        SCOPED_TRACE(solver);
        std::ofstream(dir.file("req.json"), std::ios::binary) << "{\"machine\":\"TTTRR\",\"gamma_r\xC0"
                                                                 "d\":0.5}";
        const auto r = run(dir, std::string("solve ") + solver + " --input " + dir.file("req.json"));
        EXPECT_EQ(r.code, 2) << r.err;
        const auto j = nlohmann::json::parse(r.err, nullptr, false);
        ASSERT_TRUE(j.is_object()) << r.err;
        EXPECT_NE(j.at("error").get<std::string>().find("malformed JSON"), std::string::npos) << r.err;
    }
}

// fuzz_readings: a number past double in a JSON value ("1e999") made the JSON library throw out_of_range,
// which only parse errors were caught for: `import` ended with the library's message, and `solve` with
// exit 1. Every JSON input now refuses it as malformed, exit 2.
TEST(CliFuzzFindings, ANumberPastDoubleInJsonIsRefusedAsMalformed) {
    TempDir dir;
    std::ofstream(dir.file("r.csv")) << "# ballbar-readings/1\n"
                                        "# machine: {\"type\":\"TTTRR\",\"c_offset_mm\":[0,0,1e999]}\n"
                                        "time_s,location,point,X_mm,Y_mm,Z_mm,A_deg,C_deg,socket_x_mm,socket_y_mm,"
                                        "socket_z_mm,measured_mm\n"
                                        "12.0,0,0,32.375,-14.312,-120.042,0,0,-49.275,-14.312,-77.777,100.0021\n";
    const auto imported = run(dir, "import " + dir.file("r.csv"));
    EXPECT_EQ(imported.code, 2) << imported.err;
    EXPECT_NE(imported.err.find("line 2"), std::string::npos) << imported.err;
    EXPECT_EQ(imported.err.find("error: [json.exception"), std::string::npos)
        << imported.err;  // ours, not the library's

    std::ofstream(dir.file("req.json")) << R"({"socket_mm":[0,0,1e999],"points_mm":[],"delta_l_mm":[]})";
    const auto solved = run(dir, "solve ssm --input " + dir.file("req.json"));
    EXPECT_EQ(solved.code, 2) << solved.err;
    EXPECT_NE(solved.err.find("malformed JSON"), std::string::npos) << solved.err;
}

}  // namespace
