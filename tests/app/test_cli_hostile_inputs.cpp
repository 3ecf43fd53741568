// SPDX-License-Identifier: MIT
// Inputs that can't hurt (issue 15, items 1, 2 and 6), through the real `ballbar` process:
//  - every command that reads a file, given /dev/zero, a FIFO nobody writes, a sparse 10 GB file or a
//    directory, exits 2 at once (well within the test's timeout) with a message naming the problem, in
//    bounded memory (the run has a 1 GB address-space limit outside sanitizer builds);
//  - every command that writes refuses to write over its inputs or the database (compared by device
//    and inode: a hard link is caught too), refuses a symlink at the output path, and neither follows
//    nor deletes a planted OUT.tmp / OUT.part symlink;
//  - messages cut long tokens and name an exponent in an NC program as a malformed number.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "../sanitizers.hpp"
#include "cli_harness.hpp"

using namespace ballbar::test;
namespace fs = std::filesystem;

namespace {

using ballbar::test::kSanitized;  // ASan reserves terabytes of address space: no ulimit -v then

const std::string kDataHostileInputs = BALLBAR_TEST_DATA_DIR;

std::string q(const std::string& s) {
    return "'" + s + "'";
}

/// run() with a hard timeout (a hang fails instead of blocking the suite), the address space capped
/// at 1 GB and the wall time measured.
struct TimedRun {
    CliRun r;
    double seconds = 0;
};
TimedRun run_bounded(const TempDir& d, const std::string& args, const std::string& input = "") {
    const std::string limit = kSanitized ? "" : "ulimit -v 1000000; ";
    std::ofstream(d.path / "stdin") << input;
    const std::string cmd = "(" + limit + "exec timeout -s KILL 20 " + q(BALLBAR_EXE) + " --db " +
                            q(d.file("test.db")) + " " + args + ") <" + q(d.file("stdin")) + " >" +
                            q(d.file("stdout")) + " 2>" + q(d.file("stderr"));
    std::ofstream(d.path / "run.sh") << cmd << '\n';
    const auto t0 = std::chrono::steady_clock::now();
    const int status = std::system(("bash " + q(d.file("run.sh"))).c_str());
    TimedRun t;
    t.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    t.r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    t.r.out = slurp(d.path / "stdout");
    t.r.err = slurp(d.path / "stderr");
    return t;
}

std::string model_json() {
    return R"({"format": "ballbar-model/1",
  "machine": {"type": "TTTRR", "name": "m", "a_pivot_mm": [0, 0, 0], "c_offset_mm": [0, 0, -100],
              "tool_ball_mm": [0, 0, 0]},
  "params": {"Y0A": 0.025, "X0C": 0.035}})";
}
const std::string kProgram = "%\nG90\nG1 X50 Y0 Z30 A30 C0 F1000\nG1 X0 Y50 A30 C90\nM30\n%\n";

/// A scratch directory with good inputs and the four hostile ones.
struct Hostile : TempDir {
    std::string machine = kDataHostileInputs + "/machines/tttrr.json";
    std::string readings = kDataHostileInputs + "/readings/spec_example.csv";
    Hostile() {
        std::ofstream(path / "model.json") << model_json();
        std::ofstream(path / "in.nc") << kProgram;
        if (::mkfifo(file("fifo").c_str(), 0600) != 0) throw std::runtime_error("mkfifo failed");
        { std::ofstream(path / "sparse"); }
        fs::resize_file(path / "sparse", 10ull << 30);  // 10 GB of holes: no disk used
        fs::create_directory(path / "dir");
    }
    /// (name, path, what the message must say)
    std::vector<std::array<std::string, 3>> cases() const {
        return {{"/dev/zero", "/dev/zero", "character device"},
                {"a FIFO", file("fifo"), "FIFO"},
                {"a sparse 10 GB file", file("sparse"), ""},
                {"a directory", file("dir"), "is a directory"}};
    }
};

struct ReaderCase {
    const char* name;
    const char* args;         ///< "{}" is the hostile path; M machine, P program, MODEL model, OUT an output
    const char* big_message;  ///< what the 10 GB file is told
};

std::string expand(std::string args, const Hostile& h, const std::string& hostile) {
    auto replace = [&](const std::string& key, const std::string& value) {
        for (auto p = args.find(key); p != std::string::npos; p = args.find(key, p + value.size()))
            args.replace(p, key.size(), value);
    };
    replace("{}", q(hostile));
    replace("MODEL", q(h.file("model.json")));
    replace("PROG", q(h.file("in.nc")));
    replace("MACH", q(h.machine));
    replace("OUT", q(h.file("out.txt")));
    return args;
}

class CliHostileInput : public ::testing::TestWithParam<ReaderCase> {};

TEST_P(CliHostileInput, DevZeroFifoHugeFileAndDirectoryAreRefusedAtOnce) {
    Hostile h;
    for (const auto& [label, hostile, says] : h.cases()) {
        const TimedRun t = run_bounded(h, expand(GetParam().args, h, hostile));
        SCOPED_TRACE(std::string(GetParam().name) + " given " + label + ": " + t.r.err);
        EXPECT_EQ(t.r.code, 2);
        // The one error format ("solve" answers in JSON on stderr, as it does for every error).
        EXPECT_TRUE(t.r.err.rfind("ballbar: error: ", 0) == 0 || t.r.err.rfind("{\"error\":", 0) == 0);
        const std::string expected = says.empty() ? GetParam().big_message : says;
        EXPECT_NE(t.r.err.find(expected), std::string::npos) << "expected \"" << expected << "\"";
        EXPECT_LT(t.seconds, 10.0) << "refused in " << t.seconds << " s";  // ~0.05 s on a quiet machine
        EXPECT_LT(t.r.err.size(), 1000u);
        EXPECT_FALSE(fs::exists(h.path / "out.txt"));
    }
}

INSTANTIATE_TEST_SUITE_P(
    EveryReader, CliHostileInput,
    ::testing::Values(ReaderCase{"import", "import {}", "longer than 1048576 bytes"},
                      ReaderCase{"identify", "identify {}", "too large"},
                      ReaderCase{"discover", "discover {}", "too large"},
                      ReaderCase{"circle_analyze", "circle analyze {}", "too large"},
                      ReaderCase{"measure_machine", "measure --dry-run --machine {}", "too large"},
                      ReaderCase{"measure_plan", "measure --dry-run --machine MACH --plan {}", "too large"},
                      ReaderCase{"circle_plan_machine",
                                 "circle plan --plane XY --radius 100 --feed 1000 --machine {} --out OUT", "too large"},
                      ReaderCase{"compensate_model", "compensate --model {} --program PROG --out OUT", "too large"},
                      ReaderCase{"compensate_program", "compensate --model MODEL --program {} --out OUT", "too large"},
                      ReaderCase{"compensate_offsets", "compensate --model MODEL --program PROG --offsets {} --out OUT",
                                 "too large"},
                      ReaderCase{"solve_ssm", "solve ssm --input {}", "too large"},
                      ReaderCase{"solve_compensate", "solve compensate --input {}", "too large"},
                      ReaderCase{"demo_plan", "demo --plan {}", "too large"},
                      ReaderCase{"demo_faults", "demo --faults {}", "too large"},
                      ReaderCase{"emulate_config", "emulate --pty --config {}", "too large"}),
    [](const auto& param_info) { return std::string(param_info.param.name); });

TEST(CliHostileStdin, SolveReadsAtMost16MiBOfStandardInput) {
    TempDir d;
    const TimedRun t = run_bounded(d, "solve ssm < /dev/zero");
    EXPECT_EQ(t.r.code, 2) << t.r.err;
    EXPECT_NE(t.r.err.find("too large"), std::string::npos) << t.r.out << t.r.err;
    EXPECT_LT(t.seconds, 10.0);
}

// ---- Safe outputs ---------------------------------------------------------------------------------

/// A database with one imported session, a victim file for planted links, and helpers.
struct Outputs : TempDir {
    const std::string victim = file("victim");
    Outputs() {
        const CliRun r = run(*this, "import " + q(kDataHostileInputs + "/readings/spec_example.csv"));
        if (r.code != 0) throw std::runtime_error("import failed: " + r.err);
        std::ofstream(victim) << "victim\n";
        std::ofstream(path / "model.json") << model_json();
        std::ofstream(path / "in.nc") << kProgram;
        std::ofstream(path / "machine.json") << slurp(kDataHostileInputs + "/machines/tttrr.json");
    }
    std::string db() const { return file("test.db"); }
    /// Plants OUT.tmp and OUT.part symlinks to the victim.
    void plant(const std::string& out) const {
        fs::create_symlink(victim, out + ".tmp");
        fs::create_symlink(victim, out + ".part");
    }
    void expect_planted_untouched(const std::string& out) const {
        EXPECT_EQ(slurp(victim), "victim\n");
        EXPECT_TRUE(fs::is_symlink(out + ".tmp")) << "a planted link is never deleted";
        EXPECT_TRUE(fs::is_symlink(out + ".part"));
        for (const auto& e : fs::directory_iterator(path))  // no temporary file of ours is left
            EXPECT_EQ(e.path().string().find(".part", out.size() + 1), std::string::npos) << e.path();
    }
};

struct WriterCase {
    const char* name;
    const char* args;    ///< "{}" is the output path
    const char* inputs;  ///< which of the outputs it must refuse: D database, M machine, P program, L model
    const char* magic;   ///< what a good output starts with
};

std::string expand_out(std::string args, const Outputs& o, const std::string& out) {
    auto replace = [&](const std::string& key, const std::string& value) {
        for (auto p = args.find(key); p != std::string::npos; p = args.find(key, p + value.size()))
            args.replace(p, key.size(), value);
    };
    replace("{}", q(out));
    replace("MODEL", q(o.file("model.json")));
    replace("PROG", q(o.file("in.nc")));
    replace("MACH", q(o.file("machine.json")));
    return args;
}

class CliSafeOutput : public ::testing::TestWithParam<WriterCase> {};

TEST_P(CliSafeOutput, NeverOverAnInputNeverThroughALinkNeverAPlantedTemporary) {
    Outputs o;
    const WriterCase& c = GetParam();
    // 1. Over one of its inputs or the database (by name and through a hard link): exit 2, unchanged.
    std::vector<std::pair<std::string, std::string>> inputs;
    for (const char* k = c.inputs; *k; ++k) {
        if (*k == 'D') inputs.push_back({o.db(), "database"});
        if (*k == 'M') inputs.push_back({o.file("machine.json"), "machine file"});
        if (*k == 'P') inputs.push_back({o.file("in.nc"), "program"});
        if (*k == 'L') inputs.push_back({o.file("model.json"), "model file"});
    }
    for (const auto& [input, role] : inputs) {
        const std::string before = slurp(input);
        fs::create_hard_link(input, o.file("alias"));
        for (const std::string& target : {input, o.file("alias")}) {
            const CliRun r = run(o, expand_out(c.args, o, target));
            SCOPED_TRACE(std::string(c.name) + " --out " + target + ": " + r.err);
            EXPECT_EQ(r.code, 2);
            EXPECT_NE(r.err.find("is the " + role), std::string::npos);
            EXPECT_EQ(slurp(input), before);
        }
        fs::remove(o.file("alias"));
    }
    // 2. A symlink at the output path: refused, neither the link nor its target changed.
    const std::string link = o.file("link.out");
    fs::create_symlink(o.victim, link);
    CliRun r = run(o, expand_out(c.args, o, link));
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("is a symbolic link"), std::string::npos) << r.err;
    EXPECT_TRUE(fs::is_symlink(link));
    EXPECT_EQ(slurp(o.victim), "victim\n");
    // 3. Planted OUT.tmp and OUT.part links: the output is written, the victim and the links untouched.
    const std::string out = o.file("new.out");
    o.plant(out);
    r = run(o, expand_out(c.args, o, out));
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(slurp(out).rfind(c.magic, 0), 0u) << slurp(out).substr(0, 80);
    EXPECT_FALSE(fs::is_symlink(out));
    o.expect_planted_untouched(out);
    // 4. Over an existing regular file: replaced, keeping its permissions.
    std::ofstream(o.file("old.out")) << "old\n";
    fs::permissions(o.file("old.out"), fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
    r = run(o, expand_out(c.args, o, o.file("old.out")));
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(slurp(o.file("old.out")).rfind(c.magic, 0), 0u);
    EXPECT_EQ(fs::status(o.file("old.out")).permissions() & fs::perms::all,
              fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
    // 5. A directory: "is a directory".
    fs::create_directory(o.file("adir"));
    r = run(o, expand_out(c.args, o, o.file("adir")));
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("is a directory"), std::string::npos) << r.err;
}

INSTANTIATE_TEST_SUITE_P(
    EveryWriter, CliSafeOutput,
    ::testing::Values(WriterCase{"export_readings", "export 1 --format readings --out {}", "D", "# ballbar-readings/1"},
                      WriterCase{"export_json", "export 1 --format json --out {}", "D", "{"},
                      WriterCase{"report", "report 1 --out {}", "D", "%PDF"},
                      WriterCase{"measure_dry_run_program", "measure --dry-run --machine MACH --program {}", "M", "%"},
                      WriterCase{"compensate", "compensate --model MODEL --program PROG --out {}", "DPL", "%"},
                      WriterCase{"circle_plan",
                                 "circle plan --plane XY --radius 100 --feed 1000 --machine MACH --out {}", "DM", "%"},
                      WriterCase{"circle_plan_test_out",
                                 "circle plan --plane XY --radius 100 --feed 1000 --out - --test-out {}", "D", "{"}),
    [](const auto& param_info) { return std::string(param_info.param.name); });

TEST(CliSafeOutputDemo, ReportIsNeverTheDatabaseNorALink) {
    Outputs o;
    const std::string before = slurp(o.db());
    CliRun r = run(o, "demo --report " + q(o.db()));
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("is the database"), std::string::npos) << r.err;
    EXPECT_EQ(slurp(o.db()), before) << "refused before the demo ran";
    fs::create_symlink(o.victim, o.file("link.pdf"));
    r = run(o, "demo --report " + q(o.file("link.pdf")));
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("is a symbolic link"), std::string::npos) << r.err;
    EXPECT_EQ(slurp(o.victim), "victim\n");
}

TEST(CliSafeOutputCsv, CsvFilesAreNeverWrittenThroughLinks) {
    Outputs o;
    fs::create_directory(o.file("csv"));
    fs::create_symlink(o.victim, o.file("csv/points.csv"));
    CliRun r = run(o, "export 1 --format csv --out " + q(o.file("csv")));
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("is a symbolic link"), std::string::npos) << r.err;
    EXPECT_EQ(slurp(o.victim), "victim\n");
    fs::remove(o.file("csv/points.csv"));
    fs::create_hard_link(o.db(), o.file("csv/samples.csv"));
    const std::string before = slurp(o.db());
    r = run(o, "export 1 --format csv --out " + q(o.file("csv")));
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("is the database"), std::string::npos) << r.err;
    EXPECT_EQ(slurp(o.db()), before);
    fs::remove(o.file("csv/samples.csv"));
    r = run(o, "export 1 --format csv --out " + q(o.file("csv")));
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_FALSE(slurp(o.file("csv/points.csv")).empty());
}

// ---- Messages -------------------------------------------------------------------------------------

TEST(CliHostileMessages, LongTokensAreCutAndAnExponentIsAMalformedNumber) {
    TempDir d;
    std::ofstream(d.path / "model.json") << model_json();
    // A 1 MB malformed number in a readings file: the message holds 40 bytes of it and "…".
    std::string text = slurp(kDataHostileInputs + "/readings/spec_example.csv");
    const auto last = text.rfind("100.0021");
    ASSERT_NE(last, std::string::npos);
    text.replace(last, 8, std::string(1'000'000, '7') + "x");
    std::ofstream(d.path / "long.csv") << text;
    CliRun r = run(d, "import " + q(d.file("long.csv")));
    EXPECT_EQ(r.code, 2) << r.err.substr(0, 300);
    EXPECT_LT(r.err.size(), 400u) << r.err.substr(0, 300);
    EXPECT_NE(r.err.find(std::string(40, '7') + "…"), std::string::npos) << r.err;
    // 1e308 in an NC program: a malformed number, not "unsupported word E".
    for (const char* word : {"X1e308", "X1E5", "F1e-300"}) {
        std::ofstream(d.path / "e.nc") << "%\nG90\nG1 " << word << " Y0 Z30 A30 C0 F1000\nM30\n%\n";
        r = run(d, "compensate --model " + q(d.file("model.json")) + " --program " + q(d.file("e.nc")) + " --out " +
                       q(d.file("out.nc")));
        EXPECT_EQ(r.code, 2) << r.err;
        EXPECT_NE(r.err.find("malformed or out-of-range number"), std::string::npos) << r.err;
        EXPECT_EQ(r.err.find("unsupported word E"), std::string::npos) << r.err;
        EXPECT_NE(r.err.find("line 3"), std::string::npos) << r.err;
    }
    // A directory given as a readings file is "a directory", not "empty file".
    fs::create_directory(d.path / "adir");
    r = run(d, "identify " + q(d.file("adir")));
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("is a directory"), std::string::npos) << r.err;
}

}  // namespace
