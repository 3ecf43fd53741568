// SPDX-License-Identifier: MIT
// `ballbar demo` as a command: its JSON and text, --faults, --compensate, the stored audit trail and
// what the other commands show of a demo session. What the demo measures (each machine type, each
// fault, within 1 µm and 2″ of the truth) is tested in process (tests/workflow/test_ssm_demo.cpp).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct DemoRun {
    int status = -1;
    std::string out;
};

DemoRun run_demo(const std::string& args) {
    DemoRun r;
    const std::string cmd = std::string(BALLBAR_EXE) + " " + args + " 2>/dev/null";
    FILE* p = ::popen(cmd.c_str(), "r");
    if (!p) return r;
    std::array<char, 4096> buf{};
    std::size_t n;
    while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
    const int st = ::pclose(p);
    r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    return r;
}

std::filesystem::path temp_db(const std::string& name) {
    const auto dir = std::filesystem::temp_directory_path() / ("ballbar-demo-test-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    const auto db = dir / name;
    std::filesystem::remove(db);
    return db;
}

/// The rows of a CSV file with a header line, as column → text.
std::vector<std::map<std::string, std::string>> read_csv(const std::filesystem::path& path) {
    std::ifstream in(path);
    std::vector<std::map<std::string, std::string>> rows;
    std::string line, cell;
    std::vector<std::string> header;
    while (std::getline(in, line)) {
        std::vector<std::string> cells;
        std::istringstream ls(line);
        while (std::getline(ls, cell, ',')) cells.push_back(cell);
        if (header.empty()) {
            header = cells;
            continue;
        }
        auto& row = rows.emplace_back();
        for (std::size_t i = 0; i < cells.size() && i < header.size(); ++i) row[header[i]] = cells[i];
    }
    return rows;
}

/// Every stored point's window [first_seq, last_seq] holds exactly its n stored samples, and their mean
/// is the point's reading less one constant (the reference): the windows name the samples that made the
/// points, also after gaps in the stream and reconnects.
void expect_windows_name_their_samples(const std::filesystem::path& db, int session) {
    const auto dir = db.parent_path() / (db.stem().string() + "-csv");
    std::filesystem::remove_all(dir);
    const DemoRun ex =
        run_demo("--db " + db.string() + " export " + std::to_string(session) + " --format csv --out " + dir.string());
    ASSERT_EQ(ex.status, 0);
    std::map<long long, double> displacement_mm;
    for (const auto& s : read_csv(dir / "samples.csv"))
        displacement_mm[std::stoll(s.at("seq"))] = std::stod(s.at("displacement_nm")) * 1e-6;
    const auto points = read_csv(dir / "points.csv");
    ASSERT_FALSE(points.empty());
    std::optional<double> offset_mm;
    for (const auto& p : points) {
        const long long first = std::stoll(p.at("first_seq")), last = std::stoll(p.at("last_seq"));
        double sum = 0;
        long long n = 0;
        for (auto it = displacement_mm.lower_bound(first); it != displacement_mm.end() && it->first <= last; ++it) {
            sum += it->second;
            ++n;
        }
        ASSERT_EQ(n, std::stoll(p.at("n"))) << "point " << p.at("index") << " window " << first << ".." << last;
        const double off = std::stod(p.at("measured_mm")) - sum / static_cast<double>(n);
        if (!offset_mm) offset_mm = off;
        EXPECT_NEAR(off, *offset_mm, 1e-6) << "point " << p.at("index");
    }
}

constexpr double kPositionTol_mm = 0.001;
constexpr double kAngleTol_rad = 2.0 / 3600.0 * 3.141592653589793 / 180.0;

// What the demo measures, for every machine type and under every fault, is the use case's own test
// (tests/workflow/test_ssm_demo.cpp, in process). Here: the command's JSON and its --faults.

TEST(Demo, JsonGivesMeasuredNextToTrueAndTheSessionId) {
    const auto db = temp_db("json.db");
    const DemoRun r = run_demo("--db " + db.string() + " demo --json --seed 3 --machine TTTRR");
    ASSERT_EQ(r.status, 0) << r.out;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j.at("machine"), "TTTRR");
    EXPECT_GE(j.at("session").get<int>(), 1);
    ASSERT_EQ(j.at("locations").size(), 8u);  // four tests, two steps
    for (const auto& l : j.at("locations")) {
        ASSERT_EQ(l.at("e_mm").size(), 3u);
        ASSERT_EQ(l.at("e_mm_std").size(), 3u);
        double d2 = 0;
        for (int k = 0; k < 3; ++k)
            d2 += std::pow(l.at("e_mm")[k].get<double>() - l.at("true_e_mm")[k].get<double>(), 2);
        EXPECT_LT(std::sqrt(d2), kPositionTol_mm) << l.dump();
    }
    ASSERT_EQ(j.at("orientation").size(), 4u);
    for (const auto& o : j.at("orientation")) {
        // A TTTRR test determines Δα and Δγ: the keys say which (d_alpha_rad, d_gamma_rad), each with its
        // uncertainty and the true value; Δβ is not there.
        EXPECT_FALSE(o.contains("d_beta_rad")) << o.dump();
        for (const char* k : {"d_alpha_rad", "d_gamma_rad"}) {
            ASSERT_TRUE(o.contains(std::string(k) + "_std")) << o.dump();
            EXPECT_NEAR(o.at(k).get<double>(), o.at(std::string("true_") + k).get<double>(), kAngleTol_rad) << k;
        }
    }
    EXPECT_EQ(j.at("truth_check").at("wrong_pose"), 0);
    // The session is stored: a second demo gets the next id.
    const DemoRun again = run_demo("--db " + db.string() + " demo --json --seed 3 --machine TTTRR");
    ASSERT_EQ(again.status, 0);
    EXPECT_EQ(nlohmann::json::parse(again.out).at("session").get<int>(), j.at("session").get<int>() + 1);
}

/// `demo --faults`: the faults reach the emulator; what the link did is stored and shown by the other
/// commands (sessions show's gaps, export's windows, the report).
TEST(Demo, FaultsFromTheCommandLineReachTheEmulatorAndTheStoredSession) {
    const auto db = temp_db("faults.db");
    const std::string faults =
        R"({"drop_frame_probability": 0.03, "corrupt_byte_probability": 0.0005, "replay_frame_probability": 0.02, "start_delay_s": 20, "feed_override": 0.5})";
    const DemoRun r =
        run_demo("--db " + db.string() + " demo --json --seed 4 --machine RTTTR --faults '" + faults + "'");
    ASSERT_EQ(r.status, 0) << r.out;
    const auto j = nlohmann::json::parse(r.out);
    const auto& tc = j.at("truth_check");
    EXPECT_GT(tc.at("dropped_frames").get<std::size_t>(), 0u) << tc.dump();
    EXPECT_GT(tc.at("replayed_frames").get<std::size_t>(), 0u) << tc.dump();
    EXPECT_EQ(tc.at("wrong_pose"), 0);
    const DemoRun rep =
        run_demo("--db " + db.string() + " report " + std::to_string(j.at("session").get<int>()) + " --json");
    EXPECT_EQ(rep.status, 0) << rep.out.substr(0, 400);
    const DemoRun shown =
        run_demo("--db " + db.string() + " sessions show " + std::to_string(j.at("session").get<int>()) + " --json");
    ASSERT_EQ(shown.status, 0) << shown.out.substr(0, 400);
    const auto gaps = nlohmann::json::parse(shown.out).at("sample_gaps");
    EXPECT_GT(gaps.size(), 0u);
    EXPECT_LE(gaps.size(), tc.at("dropped_frames").get<std::size_t>() + tc.at("corrupted_bytes").get<std::size_t>());
    expect_windows_name_their_samples(db, j.at("session").get<int>());
}

TEST(Demo, HumanOutputShowsMeasuredNextToTrue) {
    const auto db = temp_db("human.db");
    const DemoRun r = run_demo("--db " + db.string() + " demo");
    ASSERT_EQ(r.status, 0) << r.out;
    EXPECT_NE(r.out.find("measured"), std::string::npos);
    EXPECT_NE(r.out.find("true"), std::string::npos);
    EXPECT_NE(r.out.find("TTTRR"), std::string::npos);
    EXPECT_EQ(r.out.find("\033["), std::string::npos) << "no colour when stdout is not a terminal";
}

TEST(Demo, SessionsShowGivesEachResultsValuesWithUnits) {
    const auto db = temp_db("show.db");
    const DemoRun r = run_demo("--db " + db.string() + " demo --json");
    ASSERT_EQ(r.status, 0) << r.out;
    const auto id = nlohmann::json::parse(r.out)["session"].get<long>();
    const DemoRun shown = run_demo("--db " + db.string() + " sessions show " + std::to_string(id));
    ASSERT_EQ(shown.status, 0) << shown.out;
    // Each SSM location's error with its uncertainty, each test's orientation errors in arc-seconds.
    EXPECT_NE(shown.out.find("test 1 step 1: ΔV ("), std::string::npos) << shown.out;  // as measure prints it
    EXPECT_NE(shown.out.find(") ± ("), std::string::npos) << shown.out;
    EXPECT_NE(shown.out.find(" µm, e ("), std::string::npos) << shown.out;
    EXPECT_NE(shown.out.find("test 1 (BothAxes): Δα "), std::string::npos) << shown.out;
    EXPECT_NE(shown.out.find("″ Δγ "), std::string::npos) << shown.out;
}

TEST(Demo, CompensationFlagsEstimatesMoreThanFiveSigmaFromTheTruth) {
    const auto db = temp_db("flags.db");
    const DemoRun j = run_demo("--db " + db.string() + " demo --compensate --json");
    ASSERT_EQ(j.status, 0) << j.out;
    const DemoRun t = run_demo("--db " + db.string() + " demo --compensate");
    ASSERT_EQ(t.status, 0) << t.out;
    const auto identified = nlohmann::json::parse(j.out)["compensation"]["identified"];
    ASSERT_GT(identified.size(), 5u);
    for (const auto& p : identified) {
        const std::string name = p["name"];
        const auto at = t.out.find("\n  " + name + " ", t.out.find("Identified vs true"));
        ASSERT_NE(at, std::string::npos) << name << "\n" << t.out;
        const std::string line = t.out.substr(at + 1, t.out.find('\n', at + 1) - at - 1);
        EXPECT_NE(line.find(" ± "), std::string::npos) << line;
        EXPECT_NE(line.find("(true "), std::string::npos) << line;
        const bool off = p["sigma_from_identifiable"].is_number() && p["sigma_from_identifiable"].get<double>() > 5.0;
        EXPECT_EQ(line.find("σ from the identifiable value") != std::string::npos, off) << line;
        // Judged against what the plan can identify, the estimate agrees: only noise is left.
        EXPECT_FALSE(off) << line;
        // The common scale EZZ is held at zero, so the fit sees EXX − EZZ and EYY − EZZ (physics, not a bug).
        if (name == "EXX" || name == "EYY") {
            EXPECT_NEAR(p["identifiable_value"].get<double>(), p["true_value"].get<double>() - 5e-6, 0.05e-6) << name;
        }
    }
    // Units: no bare numbers in the identification's estimates.
    EXPECT_NE(t.out.find(" µm "), std::string::npos) << t.out;
    EXPECT_NE(t.out.find(" µrad "), std::string::npos) << t.out;
    EXPECT_NE(t.out.find(" µm/m "), std::string::npos) << t.out;
}

TEST(Demo, StoresTheProcedureStepsAsTheAuditTrail) {
    const auto db = temp_db("audit.db");
    const DemoRun r = run_demo("--db " + db.string() + " demo --json");
    ASSERT_EQ(r.status, 0) << r.out;
    const auto id = nlohmann::json::parse(r.out)["session"].get<long>();
    const DemoRun e = run_demo("--db " + db.string() + " export " + std::to_string(id) + " --format json --out -");
    ASSERT_EQ(e.status, 0) << e.out;
    const auto j = nlohmann::json::parse(e.out);
    // Every step of the guided procedure, in order, from connecting to the operator's acceptance ...
    const auto& steps = j["procedure"];
    ASSERT_GT(steps.size(), 20u) << e.out.substr(0, 2000);
    EXPECT_EQ(steps.front()["from"], "Connecting");
    EXPECT_EQ(steps.back()["event"], "Accepted");
    EXPECT_EQ(steps.back()["to"], "Done");
    // ... next to the stored session's lifecycle, and none of them among the results.
    EXPECT_EQ(j["transitions"].back()["to"], "completed");
    for (const auto& res : j["results"]) EXPECT_NE(res["kind"], "acquisition.transition");
}

TEST(Demo, RejectsAnUnknownMachineType) {
    const DemoRun r = run_demo("demo --machine XYZAB");
    EXPECT_EQ(r.status, 2);
}

}  // namespace
