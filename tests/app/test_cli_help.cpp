// SPDX-License-Identifier: MIT
// Every subcommand's --help ends with examples and the exit codes; the shell completion scripts are
// generated from the same command line and know every subcommand and option.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "cli_harness.hpp"

namespace ballbar::test {
namespace {

std::vector<std::string> subcommands(const TempDir& dir) {
    const CliRun r = run(dir, "completion commands");
    EXPECT_EQ(r.code, 0) << r.err;
    std::vector<std::string> names;
    std::istringstream in(r.out);
    for (std::string line; std::getline(in, line);) names.push_back(line.substr(0, line.find('\t')));
    return names;
}

TEST(CliHelp, EverySubcommandHasExamplesAndExitCodes) {
    TempDir dir;
    const auto names = subcommands(dir);
    ASSERT_GE(names.size(), 14u);
    for (const auto& name : names) {
        const CliRun r = run(dir, name + " --help");
        EXPECT_EQ(r.code, 0) << name << ": " << r.err;
        EXPECT_NE(r.out.find("Examples:\n  ballbar " + name), std::string::npos) << name << " --help has no example";
        EXPECT_NE(r.out.find("Exit codes:"), std::string::npos) << name << " --help has no exit codes";
        EXPECT_NE(r.out.find("  2  bad command line"), std::string::npos) << name;
    }
    const CliRun top = run(dir, "--help");
    EXPECT_EQ(top.code, 0);
    EXPECT_NE(top.out.find("Exit codes:"), std::string::npos);
}

TEST(CliHelp, MeasureMarksItsRequiredOptions) {
    TempDir dir;
    const CliRun r = run(dir, "measure --help");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("REQUIRED (not with --dry-run): instrument URI"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("REQUIRED (not with --resume): machine file"), std::string::npos) << r.out;
}

TEST(CliHelp, BashCompletionIsValidAndKnowsEveryCommand) {
    TempDir dir;
    const CliRun r = run(dir, "completion bash");
    ASSERT_EQ(r.code, 0) << r.err;
    std::ofstream(dir.path / "ballbar.bash") << r.out;
    EXPECT_EQ(std::system(("bash -n '" + dir.file("ballbar.bash") + "'").c_str()), 0) << r.out;
    for (const auto& name : subcommands(dir))
        EXPECT_TRUE(r.out.find(" " + name + " ") != std::string::npos ||
                    r.out.find("'" + name + " ") != std::string::npos ||
                    r.out.find(" " + name + "'") != std::string::npos)
            << name;

    // Ask the function itself, as bash would on <TAB>: `ballbar sol<TAB>` and `ballbar solve <TAB>`.
    const auto complete = [&](const std::string& words, int cword) {
        std::ofstream(dir.path / "ask.sh")
            << "source '" << dir.file("ballbar.bash") << "'\nCOMP_WORDS=(" << words << ")\nCOMP_CWORD=" << cword
            << "\n_ballbar\nprintf '%s\\n' \"${COMPREPLY[@]}\"\n";
        EXPECT_EQ(std::system(("bash '" + dir.file("ask.sh") + "' > '" + dir.file("reply") + "'").c_str()), 0);
        return slurp(dir.path / "reply");
    };
    EXPECT_EQ(complete("ballbar sol", 1), "solve\n");
    const std::string solve = complete("ballbar solve ''", 2);
    EXPECT_NE(solve.find("compensate\n"), std::string::npos) << solve;
    EXPECT_NE(solve.find("ssm\n"), std::string::npos) << solve;
    const std::string flags = complete("ballbar compensate --ex", 2);
    EXPECT_EQ(flags, "--exact\n");
}

TEST(CliHelp, ZshCompletionHasEveryCommand) {
    TempDir dir;
    const CliRun r = run(dir, "completion zsh");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.out.rfind("#compdef ballbar\n", 0), 0u);
    for (const auto& name : subcommands(dir)) EXPECT_NE(r.out.find("'" + name + ":"), std::string::npos) << name;
}

TEST(CliHelp, UnknownShellIsABadCommandLine) {
    TempDir dir;
    EXPECT_EQ(run(dir, "completion fish").code, 2);
}

}  // namespace
}  // namespace ballbar::test
