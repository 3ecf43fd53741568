// SPDX-License-Identifier: MIT
// ballbarkins in LinuxCNC itself (headless simulator, tests/linuxcnc/sim/): the joints LinuxCNC
// commands through the module, checked against LinuxCNC's own xyzac-trt-kins and against the
// independent erroneous machine of tests/independent_tttrr.hpp. ctest label `linuxcnc`, serial;
// skipped, saying why, where LinuxCNC or the module is absent.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "../independent_tttrr.hpp"
#include "linuxcnc_sim.hpp"

namespace {

namespace tt = ballbar::test::tttrr;
namespace lc = ballbar::test::lcnc;

// The machine: A axis line through (·, 20, 10), C frame 110 mm below it and 20 mm towards −Y;
// xyzac-trt-kins's equivalent: rotation point (0, 0, −100), y-offset 20, z-offset 110.
const tt::Geometry kGeometry{{0, 20, 10}, {0, -20, -110}};

std::string model_json(const tt::Errors& e) {
    std::ostringstream s;
    s << std::setprecision(17) << R"({"format":"ballbar-model/1","machine":{"type":"TTTRR","name":"sim",)"
      << R"("a_pivot_mm":[0,20,10],"c_offset_mm":[0,-20,-110],"tool_ball_mm":[0,0,0]},"params":{)"
      << R"("Y0A":)" << e.Y0A << R"(,"Z0A":)" << e.Z0A << R"(,"B0A":)" << e.B0A << R"(,"C0A":)" << e.C0A << R"(,"X0C":)"
      << e.X0C << R"(,"Y0C":)" << e.Y0C << R"(,"A0C":)" << e.A0C << R"(,"B0C":)" << e.B0C << R"(,"A_zero":)" << e.A_zero
      << R"(,"C_zero":)" << e.C_zero << R"(,"EXX":)" << e.EXX << R"(,"EYY":)" << e.EYY << R"(,"C0Y":)" << e.C0Y << "}}";
    return s.str();
}

// sim/moves.ngc: seven moves that move (its first, to where the machine is, does not), each followed
// by a dwell.
constexpr std::size_t kMoves = 7;

const std::vector<std::string> kToolOffset = {"net tool-offset motion.tooloffset.z"};

// LinuxCNC's xyzac-trt-kins set to the same nominal machine (the pins ballbarkins prints at load).
std::vector<std::string> stock_kins_pins() {
    return {"setp xyzac-trt-kins.x-rot-point 0",    "setp xyzac-trt-kins.y-rot-point 0",
            "setp xyzac-trt-kins.z-rot-point -100", "setp xyzac-trt-kins.y-offset 20",
            "setp xyzac-trt-kins.z-offset 110",     kToolOffset[0] + " => xyzac-trt-kins.tool-offset"};
}

std::string program() {
    return lc::read_text(std::string(BALLBAR_LINUXCNC_SIM_DIR) + "/moves.ngc");
}

class LinuxcncSim : public ::testing::Test {
  protected:
    void SetUp() override {
        const std::string why = lc::unavailable();
        if (!why.empty()) GTEST_SKIP() << "LinuxCNC tests skipped: " << why;
    }

    // ballbarkins with the model of `errors`, identity first as LinuxCNC's switchable samples.
    lc::SimRun run_ballbarkins(const ballbar::test::ScratchDir& d, const tt::Errors& errors,
                               std::vector<std::string> halcmds = {}) {
        const std::string model = d.write("model.json", model_json(errors));
        for (const auto& h : kToolOffset) halcmds.push_back(h + " => ballbarkins.tool-offset");
        ::setenv("BALLBAR_SHOW_PINS", "ballbarkins", 1);
        auto run = lc::run_sim(d, std::string(lc::kBuildModuleName) + " model=" + model + " sparm=identityfirst",
                               program(), halcmds);
        ::unsetenv("BALLBAR_SHOW_PINS");
        return run;
    }
};

// The table point and tool axis the nominal machine gives the axis words of a sample: the world
// point itself in tool-centre-point mode, the nominal forward kinematics of the joints in joint mode.
tt::V intended_table_point(const lc::Sample& s) {
    const tt::V w{s.world[0], s.world[1], s.world[2]};
    if (s.kinstype > 0.5) return tt::table_point(kGeometry, w);  // M428: type 1 is TCP (identityfirst)
    return tt::rot_z(-tt::rad(s.world[4]), tt::rot_x(-tt::rad(s.world[3]), w - kGeometry.a_pivot) - kGeometry.c_offset);
}

double pin_value(const std::string& log, const std::string& pin) {
    std::istringstream in(log);
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream f(line);
        std::vector<std::string> cols{std::istream_iterator<std::string>(f), std::istream_iterator<std::string>()};
        // halcmd -s show pin: "COMP TYPE DIR VALUE NAME [==> SIGNAL]"
        for (std::size_t i = 0; i + 1 < cols.size(); ++i)
            if (cols[i + 1] == pin) return std::stod(cols[i]);
    }
    return std::nan("");
}

TEST_F(LinuxcncSim, AZeroErrorModelCommandsTheJointsOfLinuxcncsOwnXyzacTrtKins) {
    const ballbar::test::ScratchDir stock("lcnc-trt"), ours("lcnc-zero");
    const std::vector<std::string> trt = stock_kins_pins();
    const auto a = lc::run_sim(stock, "xyzac-trt-kins sparm=identityfirst", program(), trt);
    ASSERT_EQ(a.status, 0) << a.log;
    const auto b = run_ballbarkins(ours, tt::Errors{});
    ASSERT_EQ(b.status, 0) << b.log;
    const auto ra = lc::at_rest(a), rb = lc::at_rest(b);
    ASSERT_EQ(ra.size(), kMoves);
    ASSERT_EQ(rb.size(), ra.size());
    int tcp = 0;
    for (std::size_t line = 0; line < ra.size(); ++line) {  // `line`: the n-th rest
        const lc::Sample& sa = ra[line];
        const lc::Sample& sb = rb[line];
        tcp += sa.kinstype > 0.5;
        EXPECT_EQ(sa.kinstype, sb.kinstype) << "rest " << line;
        // halsampler writes 6 decimals: two roundings of equal values differ by at most 1e-6.
        for (std::size_t j = 0; j < 5; ++j) {
            EXPECT_NEAR(sb.world[j], sa.world[j], 1.0000001e-6) << "rest " << line << " axis " << j;
            EXPECT_NEAR(sb.joints[j], sa.joints[j], 1.0000001e-6) << "rest " << line << " joint " << j;
        }
    }
    EXPECT_EQ(tcp, 5);  // M428 after the first move, M429 before the last
}

TEST_F(LinuxcncSim, WithAnErrorModelTheToolIsOnTheProgrammedTablePointAtEveryDwell) {
    const tt::Errors e = tt::seed_like();
    const ballbar::test::ScratchDir on("lcnc-on"), off("lcnc-off");
    const auto run = run_ballbarkins(on, e);
    ASSERT_EQ(run.status, 0) << run.log;
    const auto nominal = run_ballbarkins(off, e, {"setp ballbarkins.enable 0"});
    ASSERT_EQ(nominal.status, 0) << nominal.log;
    double worst = 0, worst_off = 0;
    const auto rest = lc::at_rest(run), rest_off = lc::at_rest(nominal);
    // Corrected, the machine's home (joints 0) is not world 0: the program's first move moves too.
    ASSERT_EQ(rest.size(), kMoves + 1);
    ASSERT_EQ(rest_off.size(), kMoves);
    auto miss = [&](const lc::Sample& s) {
        const tt::Seen seen = tt::actual_tool_in_table(kGeometry, e, s.joints[0], s.joints[1], s.joints[2],
                                                       tt::rad(s.joints[3]), tt::rad(s.joints[4]), {0, 0, 0});
        return tt::norm(seen.position - intended_table_point(s));
    };
    for (std::size_t n = 0; n < rest.size(); ++n) {
        worst = std::max(worst, miss(rest[n]));
        EXPECT_LT(miss(rest[n]), 0.5e-3) << "rest " << n;
    }
    for (const lc::Sample& s : rest_off) worst_off = std::max(worst_off, miss(s));
    RecordProperty("worst_miss_um", std::to_string(worst * 1e3));
    RecordProperty("worst_miss_uncompensated_um", std::to_string(worst_off * 1e3));
    EXPECT_GT(worst_off, 20e-3);  // enable off: the nominal kinematics, tens of µm off
    // The pins: the largest correction applied, and the model's identity.
    EXPECT_GT(pin_value(run.log, "ballbarkins.max-correction-linear"), 0.02) << run.log;
    EXPECT_EQ(pin_value(nominal.log, "ballbarkins.max-correction-linear"), 0.0) << nominal.log;
}

// The module and `ballbar compensate` are one implementation: the program compensated offline and run
// through LinuxCNC's stock xyzac-trt-kins commands the joints the uncompensated program commands
// through ballbarkins, at every block end (the dwells, in order).
TEST_F(LinuxcncSim, TheModuleAndBallbarCompensateCommandTheSameJoints) {
    const tt::Errors e = tt::seed_like();
    const ballbar::test::ScratchDir offline("lcnc-offline"), online("lcnc-online");
    const std::string model = offline.write("model.json", model_json(e));
    const std::string in = offline.write("in.ngc", program());
    const std::string out = offline.file("out.ngc");
    const std::string cmd = std::string(BALLBAR_EXE) + " compensate --model '" + model + "' --program '" + in +
                            "' --out '" + out + "' --dialect linuxcnc --decimals 7 > '" + offline.file("log") +
                            "' 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << lc::read_text(offline.file("log"));
    const std::string compensated = lc::read_text(out);
    const std::vector<std::string> trt = stock_kins_pins();
    const auto a = lc::run_sim(offline, "xyzac-trt-kins sparm=identityfirst", compensated, trt);
    ASSERT_EQ(a.status, 0) << a.log;
    const auto b = run_ballbarkins(online, e);
    ASSERT_EQ(b.status, 0) << b.log;
    const auto ra = lc::at_rest(a), rb = lc::at_rest(b);
    ASSERT_EQ(ra.size(), kMoves + 1);  // the first move too: corrected, world 0 is not home
    ASSERT_EQ(rb.size(), ra.size());
    double worst = 0;
    for (std::size_t i = 0; i < ra.size(); ++i) {
        for (std::size_t j = 0; j < 3; ++j) {
            worst = std::max(worst, std::abs(ra[i].joints[j] - rb[i].joints[j]));
            EXPECT_NEAR(ra[i].joints[j], rb[i].joints[j], 0.1e-3) << "block end " << i << " joint " << j;
        }
        // The rotary words are written with 7 decimals and sampled with 6: 2e-6° apart at most.
        for (std::size_t j = 3; j < 5; ++j)
            EXPECT_NEAR(ra[i].joints[j], rb[i].joints[j], 2e-6) << "block end " << i << " joint " << j;
    }
    RecordProperty("worst_joint_difference_um", std::to_string(worst * 1e3));
}

// LinuxCNC's own five-axis CAM examples for its table-tilting machine (Debian ships them with the
// switchable sample configuration; M428/M429 switch TCP mode), run to their end through ballbarkins
// with an error model: no joint limit, no following error, no message from LinuxCNC; corrections of
// the size of the errors. Run 1000 times faster than written (the boat would take 28 min, the impeller,
// in inverse time, 27).
TEST_F(LinuxcncSim, LinuxcncsFiveAxisCamExamplesRunToTheirEndThroughTheModule) {
    const std::string demos =
        "/usr/share/doc/linuxcnc/examples/sample-configs/sim/axis/vismach/5axis/table-rotary-tilting/demos/";
    for (const char* name : {"boat-xyzac.ngc", "impeller-7bl-xyzac.ngc"}) {
        const std::string text = lc::read_text(demos + name);
        if (text.empty()) GTEST_SKIP() << demos << name << " is not installed (Debian's linuxcnc-uspace ships it)";
        const ballbar::test::ScratchDir d("lcnc-cam");
        const std::string model = d.write("model.json", model_json(tt::seed_like()));
        ::setenv("BALLBAR_SHOW_PINS", "ballbarkins", 1);
        const auto run = lc::run_sim(d, std::string(lc::kBuildModuleName) + " model=" + model + " sparm=identityfirst",
                                     text, {kToolOffset[0] + " => ballbarkins.tool-offset"}, {1000, 100});
        ::unsetenv("BALLBAR_SHOW_PINS");
        ASSERT_EQ(run.status, 0) << name << "\n" << run.log;
        ASSERT_FALSE(run.samples.empty()) << name;
        // The program ran to its end: the last line that moved is the last move of the file.
        int last_move = 0;
        bool tcp = false;
        for (const auto& s : run.samples) {
            last_move = std::max(last_move, s.line);
            tcp = tcp || s.kinstype > 0.5;
        }
        EXPECT_GT(last_move, static_cast<int>(std::count(text.begin(), text.end(), '\n')) - 10) << name;
        EXPECT_TRUE(tcp) << name << ": M428 switched to the tool-centre point";
        const double largest = pin_value(run.log, "ballbarkins.max-correction-linear");
        EXPECT_GT(largest, 0.005) << name;
        EXPECT_LT(largest, 0.2) << name;
        RecordProperty(std::string(name) + "_max_correction_um", std::to_string(largest * 1e3));
    }
}

TEST_F(LinuxcncSim, AModelThatCannotBeReadStopsTheModuleLoadingWithItsReasonInTheLog) {
    const ballbar::test::ScratchDir d("lcnc-bad");
    const std::string model = d.write("model.json", R"({"format":"ballbar-model/1","machine":{"type":"RRTTT"}})");
    const auto run = lc::run_sim(d, std::string(lc::kBuildModuleName) + " model=" + model, program());
    EXPECT_NE(run.status, 0);
    EXPECT_NE(run.log.find("ballbarkins: the model file '" + model + "'"), std::string::npos) << run.log;
    const auto absent = lc::run_sim(d, std::string(lc::kBuildModuleName) + " model=/nonexistent/model.json", program());
    EXPECT_NE(absent.status, 0);
    EXPECT_NE(absent.log.find("ballbarkins: cannot open the model file '/nonexistent/model.json'"), std::string::npos)
        << absent.log;
}

}  // namespace
