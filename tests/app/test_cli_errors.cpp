// SPDX-License-Identifier: MIT
// The one error format ("ballbar: error: …", said once), the exit codes of refused command lines, and
// readers that never create a database.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "cli_harness.hpp"

namespace ballbar::test {
namespace {

/// stderr is exactly one "ballbar: error: " line (plus CLI11's pointer to --help), and says `what`.
void expect_one_error(const CliRun& r, const std::string& what) {
    EXPECT_EQ(r.err.rfind("ballbar: error: ", 0), 0u) << r.err;
    EXPECT_EQ(r.err.find("ballbar: error: ", 1), std::string::npos) << "error said twice: " << r.err;
    EXPECT_NE(r.err.find(what), std::string::npos) << r.err;
}

TEST(CliErrors, AMistypedCommandSuggestsTheClosest) {
    TempDir dir;
    CliRun r = run(dir, "mesure --machine m.json");
    EXPECT_EQ(r.code, 2);
    expect_one_error(r, "unknown command 'mesure'; did you mean 'measure'?");
    r = run(dir, "sesions");
    EXPECT_EQ(r.code, 2);
    expect_one_error(r, "did you mean 'sessions'?");
    r = run(dir, "frobnicate");
    EXPECT_EQ(r.code, 2);
    expect_one_error(r, "unknown command 'frobnicate' (ballbar --help lists the commands)");
    EXPECT_FALSE(std::filesystem::exists(dir.file("test.db")));
}

TEST(CliErrors, AnUnknownOptionIsABadCommandLineInTheOneFormat) {
    TempDir dir;
    const CliRun r = run(dir, "demo --bogus");
    EXPECT_EQ(r.code, 2);
    expect_one_error(r, "--bogus");
    EXPECT_FALSE(std::filesystem::exists(dir.file("test.db")));
}

TEST(CliErrors, AMistypedOptionSuggestsTheClosestOfItsCommand) {
    TempDir dir;
    CliRun r = run(dir, "measure --devce serial:/dev/null --machine m.json");
    EXPECT_EQ(r.code, 2);
    expect_one_error(r, "--devce");
    EXPECT_NE(r.err.find("unknown option --devce; did you mean --device?"), std::string::npos) << r.err;
    r = run(dir, "circle measure --radus=50");  // a subcommand's option, written with =
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("did you mean --radius?"), std::string::npos) << r.err;
    r = run(dir, "demo --frobnicate");  // nothing close: no guess
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err.find("did you mean"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir.file("test.db")));
}

TEST(CliErrors, IdentifyNamesAMissingFileAndCreatesNoDatabase) {
    TempDir dir;
    CliRun r = run(dir, "identify nonexist.readings");
    EXPECT_EQ(r.code, 2);
    expect_one_error(r, "no such file: nonexist.readings");
    r = run(dir, "identify 1");
    EXPECT_EQ(r.code, 2);
    expect_one_error(r, "no database at " + dir.file("test.db") + " (check --db)");
    EXPECT_FALSE(std::filesystem::exists(dir.file("test.db")));
}

TEST(CliErrors, AMissingSessionIsSaidOnce) {
    TempDir dir;
    ASSERT_EQ(run(dir, "demo --json").code, 0);
    const CliRun r = run(dir, "report 99 --json");
    EXPECT_EQ(r.code, 2);
    expect_one_error(r, "no session");
}

}  // namespace
}  // namespace ballbar::test
