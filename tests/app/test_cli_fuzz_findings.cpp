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

}  // namespace
