// SPDX-License-Identifier: MIT
// Issue 15, item 4, from the command line: eight `ballbar --db new.db import --allow-duplicate FILE`
// processes started at once on a database that does not exist yet all succeed (the same file each time:
// without --allow-duplicate all but one are refused as duplicates) (docs/storage.md, "Several processes may open
// a new file at once").
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "cli_harness.hpp"

namespace {

TEST(CliConcurrentOpen, EightImportsIntoANewDatabaseAtOnceAllSucceed) {
    ballbar::test::TempDir dir;
    const std::string readings = std::string(BALLBAR_TEST_DATA_DIR) + "/readings/spec_example.csv";
    for (int round = 0; round < 3; ++round) {
        SCOPED_TRACE("round " + std::to_string(round));
        const std::string db = dir.file("new-" + std::to_string(round) + ".db");
        std::vector<int> codes(8, -1);
        std::vector<std::thread> threads;
        for (std::size_t i = 0; i < codes.size(); ++i) {
            threads.emplace_back([&, i] {
                const std::string cmd = std::string("'") + BALLBAR_EXE + "' --db '" + db +
                                        "' import --allow-duplicate '" + readings + "' >/dev/null 2>'" +
                                        dir.file("err" + std::to_string(i)) + "'";
                const int status = std::system(cmd.c_str());
                codes[i] = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
            });
        }
        for (auto& t : threads) t.join();
        for (std::size_t i = 0; i < codes.size(); ++i)
            EXPECT_EQ(codes[i], 0) << ballbar::test::slurp(dir.path / ("err" + std::to_string(i)));
        const std::string out = dir.file("list.json");
        ASSERT_EQ(std::system(
                      (std::string("'") + BALLBAR_EXE + "' --db '" + db + "' sessions --json >'" + out + "'").c_str()),
                  0);
        EXPECT_EQ(nlohmann::json::parse(ballbar::test::slurp(out)).size(), codes.size());
    }
}

}  // namespace
