// SPDX-License-Identifier: MIT
// Whole-process tests of `ballbar import`, `export` and `sessions`.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "cli_harness.hpp"

namespace cli_storage {
namespace {

using namespace ballbar::test;
namespace fs = std::filesystem;
using nlohmann::json;

const std::string kData = std::string(BALLBAR_TEST_DATA_DIR) + "/readings/";

TEST(CliStorage, ImportExportImportRoundTripsWithoutLoss) {
    TempDir d;
    const CliRun a = run(d, "import '" + kData + "tttrr_full_crlf.csv'");
    ASSERT_EQ(a.code, 0) << a.err;
    EXPECT_NE(a.out.find("imported 8 readings"), std::string::npos) << a.out;
    EXPECT_NE(a.err.find("unknown columns \"comment\", \"spindle_load\" ignored"), std::string::npos) << a.err;

    ASSERT_EQ(run(d, "export 1 --format readings --out '" + d.file("one.csv") + "'").code, 0);
    const CliRun b = run(d, "import '" + d.file("one.csv") + "' --json");
    ASSERT_EQ(b.code, 0) << b.err;
    EXPECT_EQ(json::parse(b.out)["session"], 2);
    EXPECT_TRUE(b.err.empty()) << "an exported file imports without warnings: " << b.err;
    ASSERT_EQ(run(d, "export 2 --format readings --out '" + d.file("two.csv") + "'").code, 0);
    EXPECT_EQ(slurp(d.file("one.csv")), slurp(d.file("two.csv")));

    const CliRun j1 = run(d, "export 1 --format json --out -");
    const CliRun j2 = run(d, "export 2 --format json --out -");
    ASSERT_EQ(j1.code, 0) << j1.err;
    const json s1 = json::parse(j1.out), s2 = json::parse(j2.out);
    EXPECT_EQ(s1["format"], "ballbar-session/1");
    EXPECT_EQ(s1["points"], s2["points"]) << "every point field survives import → export → import exactly";
    for (const char* key : {"machine", "instrument", "operator", "notes", "started_at", "metadata", "source"}) {
        EXPECT_EQ(s1["session"][key], s2["session"][key]) << key;
    }
    EXPECT_EQ(s1["session"]["operator"], "Ada Lovelace");
    EXPECT_EQ(s1["session"]["metadata"]["shop_order"]["id"], 4711);
    EXPECT_EQ(s1["points"].size(), 8u);
    EXPECT_EQ(s1["transitions"].size(), 2u);
    EXPECT_NE(s1["session"]["uuid"], s2["session"]["uuid"]);
}

TEST(CliStorage, InvalidFileExitsTwoWithLineAndImportsNothing) {
    TempDir d;
    ASSERT_EQ(run(d, "import '" + kData + "spec_example.csv'").code, 0);
    const CliRun r = run(d, "import '" + kData + "invalid/non_numeric.csv'");
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("line 5: column \"Z_mm\": \"-12O.042\" is not a finite number"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("nothing imported"), std::string::npos) << r.err;
    const CliRun list = run(d, "sessions --json");
    ASSERT_EQ(list.code, 0) << list.err;
    EXPECT_EQ(json::parse(list.out).size(), 1u);
    EXPECT_EQ(run(d, "import '" + d.file("missing.csv") + "'").code, 2);
}

TEST(CliStorage, SessionsListsAndShows) {
    TempDir d;
    const CliRun none = run(d, "sessions --json");
    EXPECT_EQ(none.code, 0) << none.err;
    EXPECT_EQ(json::parse(none.out).size(), 0u);
    EXPECT_FALSE(fs::exists(d.file("test.db"))) << "listing does not create a database";
    ASSERT_EQ(run(d, "import '" + kData + "rrttt_minimal.csv'").code, 0);
    ASSERT_EQ(run(d, "import '" + kData + "rtttr_nominal_mismatch.csv'").code, 0);
    const CliRun list = run(d, "sessions --json");
    ASSERT_EQ(list.code, 0) << list.err;
    const json l = json::parse(list.out);
    ASSERT_EQ(l.size(), 2u);
    EXPECT_EQ(l[0]["state"], "completed");
    EXPECT_EQ(l[0]["source"], "imported");
    EXPECT_EQ(l[0]["point_count"], 5);
    EXPECT_EQ(l[1]["machine"]["type"], "RTTTR");
    const std::string uuid = l[1]["uuid"];

    const CliRun show = run(d, "sessions show " + uuid.substr(0, 8) + " --json");
    ASSERT_EQ(show.code, 0) << show.err;
    EXPECT_EQ(json::parse(show.out)["session"]["id"], 2);
    const CliRun text = run(d, "sessions show 1");
    ASSERT_EQ(text.code, 0) << text.err;
    EXPECT_NE(text.out.find("created -> completed"), std::string::npos) << text.out;
    const CliRun table = run(d, "sessions");
    EXPECT_NE(table.out.find("RRTTT head-5X"), std::string::npos) << table.out;
    EXPECT_EQ(run(d, "sessions show 99").code, 2);
    EXPECT_EQ(run(d, "export 99 --format json --out -").code, 2);
}

TEST(CliStorage, ImportingTheSameContentAgainIsRefusedNamingTheSession) {
    TempDir d;
    const std::string original = kData + "rrttt_minimal.csv";
    const CliRun first = run(d, "import '" + original + "' --json");
    ASSERT_EQ(first.code, 0) << first.err;
    const json j = json::parse(first.out);
    // The stored hash is the file's SHA-256 as coreutils computes it.
    ASSERT_EQ(std::system(("sha256sum '" + original + "' > '" + d.file("sum") + "'").c_str()), 0);
    EXPECT_EQ(j.value("sha256", ""), slurp(d.path / "sum").substr(0, 64));
    EXPECT_TRUE(j["duplicate_of"].empty());

    // The same bytes under another name: refused, exit 2, naming session 1 and its file; nothing stored.
    fs::copy_file(original, d.path / "renamed.csv");
    const CliRun again = run(d, "import '" + d.file("renamed.csv") + "'");
    EXPECT_EQ(again.code, 2) << again.err;
    EXPECT_EQ(again.err.rfind("ballbar: error: ", 0), 0u) << again.err;
    EXPECT_NE(again.err.find("already imported as session 1 (imported from " + original), std::string::npos)
        << again.err;
    EXPECT_NE(again.err.find("--allow-duplicate"), std::string::npos) << again.err;
    EXPECT_EQ(json::parse(run(d, "sessions --json").out).size(), 1u);

    // One byte more is other content.
    fs::copy_file(original, d.path / "edited.csv", fs::copy_options::overwrite_existing);
    std::ofstream(d.path / "edited.csv", std::ios::app) << "\n";
    EXPECT_EQ(run(d, "import '" + d.file("edited.csv") + "'").code, 0);

    // --allow-duplicate imports it again, says which session it repeats, and records it too.
    const CliRun allowed = run(d, "import '" + original + "' --allow-duplicate --json");
    ASSERT_EQ(allowed.code, 0) << allowed.err;
    EXPECT_NE(allowed.err.find("ballbar: warning: "), std::string::npos) << allowed.err;
    EXPECT_NE(allowed.err.find("the same content as session 1"), std::string::npos) << allowed.err;
    const json k = json::parse(allowed.out);
    EXPECT_EQ(k["session"], 3);
    EXPECT_EQ(k["duplicate_of"], json::array({1}));
    const CliRun third = run(d, "import '" + original + "'");
    EXPECT_EQ(third.code, 2);
    EXPECT_NE(third.err.find("session 1 (imported from " + original + " at "), std::string::npos) << third.err;
    EXPECT_NE(third.err.find(" and 1 more"), std::string::npos) << third.err;

    // sessions show says where a session came from.
    const CliRun shown = run(d, "sessions show 1");
    EXPECT_NE(shown.out.find("imported    from " + original), std::string::npos) << shown.out;
    EXPECT_NE(shown.out.find("SHA-256 " + j.value("sha256", "")), std::string::npos) << shown.out;
}

// A trace is read once, parsed and hashed from the same bytes: the stored hash is sha256sum's, and the
// same trace again is refused.
TEST(CliStorage, ATraceIsHashedAsItWasReadAndImportedOnce) {
    TempDir d;
    const std::string trace = std::string(BALLBAR_TEST_DATA_DIR) + "/traces/spec_example.csv";
    const CliRun first = run(d, "import '" + trace + "' --json");
    ASSERT_EQ(first.code, 0) << first.err;
    ASSERT_EQ(std::system(("sha256sum '" + trace + "' > '" + d.file("sum") + "'").c_str()), 0);
    EXPECT_EQ(json::parse(first.out).value("sha256", ""), slurp(d.path / "sum").substr(0, 64));
    const CliRun again = run(d, "import '" + trace + "'");
    EXPECT_EQ(again.code, 2) << again.err;
    EXPECT_NE(again.err.find("already imported as session 1"), std::string::npos) << again.err;
}

TEST(CliStorage, NominalDisagreementIsReported) {
    TempDir d;
    const CliRun r = run(d, "import '" + kData + "rtttr_nominal_mismatch.csv'");
    EXPECT_EQ(r.code, 0);
    EXPECT_NE(r.err.find("1 row(s) give a nominal_mm"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("lines 5"), std::string::npos) << r.err;
}

TEST(CliStorage, CsvExportWritesPointsAndSamples) {
    TempDir d;
    ASSERT_EQ(run(d, "import '" + kData + "tttrr_full_crlf.csv'").code, 0);
    const CliRun r = run(d, "export 1 --format csv --out '" + d.file("csv") + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string points = slurp(d.file("csv/points.csv"));
    EXPECT_EQ(std::count(points.begin(), points.end(), '\n'), 9);
    EXPECT_EQ(points.rfind("index,location,point,step,X_mm", 0), 0u);
    EXPECT_EQ(slurp(d.file("csv/samples.csv")), "seq,device_time_us,displacement_nm,flags,bar_temp_C\n");

    // --out NAME.csv names files, not a directory to make: NAME-points.csv and NAME-samples.csv.
    const CliRun f = run(d, "export 1 --format csv --out '" + d.file("session.csv") + "'");
    ASSERT_EQ(f.code, 0) << f.err;
    EXPECT_FALSE(std::filesystem::exists(d.file("session.csv"))) << "no directory named session.csv";
    EXPECT_EQ(slurp(d.file("session-points.csv")), points);
    EXPECT_EQ(slurp(d.file("session-samples.csv")), "seq,device_time_us,displacement_nm,flags,bar_temp_C\n");
    EXPECT_NE(f.err.find("session-points.csv and "), std::string::npos) << f.err;
}

TEST(CliStorage, NewerDatabaseIsRefused) {
    TempDir d;
    ASSERT_EQ(run(d, "import '" + kData + "spec_example.csv'").code, 0);
    ASSERT_EQ(std::system(("sqlite3 '" + d.file("test.db") + "' 'PRAGMA user_version = 99' >/dev/null").c_str()), 0);
    const std::string before = slurp(d.file("test.db"));
    const CliRun r = run(d, "sessions");
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("newer than this ballbar"), std::string::npos) << r.err;
    EXPECT_EQ(slurp(d.file("test.db")), before);
}

/// Issue 24: a damaged database was listed without a word (17,841 of 178,653 samples). Readers read
/// what they can, say that the file is damaged, and exit 1; the file is not changed.
TEST(CliStorage, ADamagedDatabaseIsReadWithAWarningAndExitOne) {
    TempDir d;
    ASSERT_EQ(run(d, "import '" + kData + "tttrr_full_crlf.csv'").code, 0);
    const std::string db = d.file("test.db");
    const auto query = [&](const std::string& sql) {
        std::string text;
        FILE* p = ::popen(("sqlite3 '" + db + "' \"" + sql + "\"").c_str(), "r");
        char buf[256];
        while (p && std::fgets(buf, sizeof buf, p)) text += buf;
        if (p) ::pclose(p);
        return std::stol(text.empty() ? "0" : text);
    };
    const long page = query("PRAGMA page_size");
    const long root = query("SELECT rootpage FROM sqlite_schema WHERE name = 'imports_by_content'");
    ASSERT_GT(root, 1);
    ASSERT_FALSE(fs::exists(db + "-wal"));
    {
        // An index's page (one listing does not read): its cell pointers point into nowhere (SQLite's quick check sees
        // it).
        std::fstream f(db, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp((root - 1) * page + 8);
        f.write("\xde\xad\xbe\xef\xde\xad\xbe\xef\xff\xff\xff\xff", 12);
    }
    const std::string before = slurp(db);
    const CliRun list = run(d, "sessions");
    EXPECT_EQ(list.code, 1) << list.out << list.err;
    EXPECT_NE(list.err.find("warning: " + db + " is damaged"), std::string::npos) << list.err;
    EXPECT_NE(list.err.find("may be incomplete"), std::string::npos) << list.err;
    EXPECT_NE(list.out.find("completed"), std::string::npos) << "the sessions table is intact: " << list.out;
    EXPECT_EQ(run(d, "sessions --json").code, 1);
    EXPECT_EQ(slurp(db), before) << "a reader changed a damaged file";
}

}  // namespace
}  // namespace cli_storage
