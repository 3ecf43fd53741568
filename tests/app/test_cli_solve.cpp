// SPDX-License-Identifier: MIT
// Whole-process tests of `ballbar solve`: JSON in, JSON out, exit codes, errors naming the field.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

struct Proc {
    int code = -1;
    std::string out, err;
};

std::string slurp_solve(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

/// Runs `ballbar <args>` with `input` on stdin; captures stdout, stderr and the exit code.
Proc run_solve(const std::string& args, const std::string& input = "") {
    char tmpl[] = "/tmp/ballbar-cli-solve-XXXXXX";
    const char* dir = ::mkdtemp(tmpl);
    EXPECT_NE(dir, nullptr);
    const fs::path d(dir);
    std::ofstream(d / "in") << input;
    const std::string cmd = std::string("'") + BALLBAR_EXE + "' " + args + " <'" + (d / "in").string() + "' >'" +
                            (d / "out").string() + "' 2>'" + (d / "err").string() + "'";
    const int status = std::system(cmd.c_str());
    Proc r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp_solve(d / "out");
    r.err = slurp_solve(d / "err");
    fs::remove_all(d);
    return r;
}

/// The JSON error on stderr of a refused request: exit code 2 and the named field.
void expect_field_error_solve(const Proc& r, const std::string& field) {
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
    json e;
    ASSERT_NO_THROW(e = json::parse(r.err)) << r.err;
    EXPECT_TRUE(e.contains("error")) << r.err;
    EXPECT_EQ(e.value("field", std::string("<none>")), field) << r.err;
}

using V3 = std::array<double, 3>;

double norm_solve(const V3& v) {
    return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/// Cube-corner points around +Z: 54.7356° cone, 120° apart.
json cube_corner(const V3& s, double length, json& deltas, const V3& e) {
    json pts = json::array();
    deltas = json::array();
    const double th = std::acos(1.0 / std::sqrt(3.0));
    for (int k = 0; k < 3; ++k) {
        const double az = 2.0 * M_PI / 3.0 * k;
        const V3 p{s[0] + length * std::sin(th) * std::cos(az), s[1] + length * std::sin(th) * std::sin(az),
                   s[2] + length * std::cos(th)};
        pts.push_back(p);
        const V3 d{p[0] - s[0], p[1] - s[1], p[2] - s[2]};
        deltas.push_back(norm_solve({d[0] + e[0], d[1] + e[1], d[2] + e[2]}) - norm_solve(d));
    }
    return pts;
}

json ssm_request(const V3& e) {
    const V3 socket{10, -20, 30};
    json dl;
    json pts = cube_corner(socket, 100, dl, e);
    return {{"socket_mm", socket}, {"points_mm", pts}, {"delta_l_mm", dl}, {"std_mm", 0.0005}};
}

json table1_case(int i) {
    std::ifstream in(std::string(BALLBAR_TEST_DATA_DIR) + "/table1.json");
    return json::parse(in).at(static_cast<std::size_t>(i));
}

void expect_rel(double got, double want, double rel = 1e-10) {
    EXPECT_NEAR(got, want, rel * std::abs(want) + 1e-15);
}

}  // namespace

TEST(CliSolve, SsmFromStdinRecoversTheError) {
    const V3 e{0.1, -0.2, 0.3};
    const Proc r = run_solve("solve ssm", ssm_request(e).dump());
    ASSERT_EQ(r.code, 0) << r.err;
    const json out = json::parse(r.out);
    for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(out["exact_mm"][i].get<double>(), e[static_cast<std::size_t>(i)], 1e-9);
        EXPECT_NEAR(out["linear_mm"][i].get<double>(), e[static_cast<std::size_t>(i)], 1e-2);
        EXPECT_NEAR(out["exact_mm_std"][i].get<double>(), 0.0005, 5e-6);  // orthogonal layout: ≈ σ per component
    }
    EXPECT_NEAR(out["condition_number"].get<double>(), 1.0, 1e-9);
    EXPECT_TRUE(out["residual_rms_mm"].is_null());
}

TEST(CliSolve, SsmFromInputFileWithSixPoints) {
    // Six points on the 54.74° cone, given with nominal lengths; the residual RMS is reported.
    const double th = std::acos(1.0 / std::sqrt(3.0));
    const V3 e{0.05, 0.02, -0.04};
    json pts = json::array(), dl = json::array();
    for (int k = 0; k < 6; ++k) {
        const double az = M_PI / 3.0 * k;
        const V3 d{150 * std::sin(th) * std::cos(az), 150 * std::sin(th) * std::sin(az), 150 * std::cos(th)};
        pts.push_back(d);
        dl.push_back(norm_solve({d[0] + e[0], d[1] + e[1], d[2] + e[2]}) - 150.0);
    }
    const json req6{{"socket_mm", {0, 0, 0}},
                    {"points_mm", pts},
                    {"delta_l_mm", dl},
                    {"nominal_mm", {150, 150, 150, 150, 150, 150}}};
    const fs::path file = fs::temp_directory_path() / ("ballbar-solve-" + std::to_string(::getpid()) + ".json");
    std::ofstream(file) << req6.dump();
    const Proc r = run_solve("solve ssm --input '" + file.string() + "'");
    fs::remove(file);
    ASSERT_EQ(r.code, 0) << r.err;
    const json out = json::parse(r.out);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(out["exact_mm"][i].get<double>(), e[static_cast<std::size_t>(i)], 1e-9);
    ASSERT_TRUE(out["residual_rms_mm"].is_number());
    EXPECT_LT(out["residual_rms_mm"].get<double>(), 1e-12);
    EXPECT_EQ(out["reading_sd_mm"].get<double>(), 0.0005);  // the documented default
}

TEST(CliSolve, OrientationRrtttTable1) {
    for (int i = 0; i < 5; ++i) {
        const json c = table1_case(i);
        const json req{{"machine", "RRTTT"},
                       {"pivot_mm", {c["x1"], c["y1"], c["z1"]}},
                       {"tool_ball_mm", {0, 0, c["zr"]}},
                       {"alpha_rad", c["alpha_rad"]},
                       {"beta_rad", c["beta_rad"]},
                       {"dV1_mm", {c["dxV1"], c["dyV1"], c["dzV1"]}},
                       {"dV2_mm", {c["dxV2"], c["dyV2"], c["dzV2"]}}};
        const Proc r = run_solve("solve orientation", req.dump());
        ASSERT_EQ(r.code, 0) << r.err;
        const json out = json::parse(r.out);
        expect_rel(out["first_order"]["d_beta_rad"], c["eq6_dbeta_rad"]);
        expect_rel(out["first_order"]["d_alpha_rad"], c["eq7_dalpha_rad"]);
        expect_rel(out["exact"]["d_alpha_rad"], c["exact_dalpha_rad"]);
        expect_rel(out["exact"]["d_beta_rad"], c["exact_dbeta_rad"]);
        expect_rel(out["nominal_after_mm"][2], c["z2"]);
        EXPECT_TRUE(out.at("singular").is_null());
    }
}

TEST(CliSolve, OrientationTttrrRecoversInjectedErrors) {
    // s = P1 + Rx(α)·([0,0,zag] + Rz(γ)·p); actual with α+Δα, γ+Δγ and P1+ΔV1.
    const V3 p1{5, -10, 20}, p{60, 40, -30}, dv1{0.01, -0.02, 0.03};
    const double zag = -100, a = 0.3, g = 0.7, da = 0.002, dg = -0.0015;
    auto point = [&](double aa, double gg, const V3& base) {
        const double wx = p[0] * std::cos(gg) - p[1] * std::sin(gg), wy = p[0] * std::sin(gg) + p[1] * std::cos(gg);
        const double wz = p[2] + zag;
        return V3{base[0] + wx, base[1] + std::cos(aa) * wy - std::sin(aa) * wz,
                  base[2] + std::sin(aa) * wy + std::cos(aa) * wz};
    };
    const V3 nom = point(a, g, p1);
    const V3 act = point(a + da, g + dg, {p1[0] + dv1[0], p1[1] + dv1[1], p1[2] + dv1[2]});
    const json req{{"machine", "TTTRR"},
                   {"a_pivot_mm", p1},
                   {"c_offset_mm", {0, 0, zag}},
                   {"socket_mm", p},
                   {"alpha_rad", a},
                   {"gamma_rad", g},
                   {"dV1_mm", dv1},
                   {"dV2_mm", {act[0] - nom[0], act[1] - nom[1], act[2] - nom[2]}}};
    const Proc r = run_solve("solve orientation", req.dump());
    ASSERT_EQ(r.code, 0) << r.err;
    const json out = json::parse(r.out);
    EXPECT_NEAR(out["exact"]["d_alpha_rad"].get<double>(), da, 1e-11);
    EXPECT_NEAR(out["exact"]["d_gamma_rad"].get<double>(), dg, 1e-11);
    EXPECT_NEAR(out["first_order"]["d_alpha_rad"].get<double>(), da, 1e-4);
    EXPECT_NEAR(out["first_order"]["d_gamma_rad"].get<double>(), dg, 1e-4);
    EXPECT_FALSE(out["exact"].contains("d_beta_rad"));
    for (int i = 0; i < 3; ++i)
        EXPECT_NEAR(out["nominal_after_mm"][i].get<double>(), nom[static_cast<std::size_t>(i)], 1e-12);
}

TEST(CliSolve, OrientationRtttrPartsAndSingular) {
    // Spindle at β = 90°: first order singular, exact answers; table part regular.
    const double db = 0.001, da = -0.002, alpha = 0.4;
    const V3 t{0, 50, 80};
    const double ca = std::cos(alpha + da), sa = std::sin(alpha + da), c0 = std::cos(alpha), s0 = std::sin(alpha);
    const json req{
        {"machine", "RTTTR"},
        {"spindle",
         {{"pivot_mm", {0, 0, 400}},
          {"tool_ball_mm", {0, 0, -200}},
          {"beta_rad", M_PI / 2},
          {"dV1_mm", {0, 0, 0}},
          {"dV2_mm",
           {-200 * std::sin(M_PI / 2 + db) + 200, 0, -200 * std::cos(M_PI / 2 + db) + 200 * std::cos(M_PI / 2)}}}},
        {"table",
         {{"a_pivot_mm", {0, 0, 0}},
          {"socket_mm", t},
          {"alpha_rad", alpha},
          {"dV1_mm", {0, 0, 0}},
          {"dV2_mm",
           {0, (t[1] * ca - t[2] * sa) - (t[1] * c0 - t[2] * s0),
            (t[1] * sa + t[2] * ca) - (t[1] * s0 + t[2] * c0)}}}}};
    const Proc r = run_solve("solve orientation", req.dump());
    ASSERT_EQ(r.code, 0) << r.err;
    const json out = json::parse(r.out);
    EXPECT_TRUE(out["first_order"]["d_beta_rad"].is_null());
    EXPECT_NEAR(out["first_order"]["d_alpha_rad"].get<double>(), da, 1e-5);
    EXPECT_NEAR(out["exact"]["d_beta_rad"].get<double>(), db, 1e-12);
    EXPECT_NEAR(out["exact"]["d_alpha_rad"].get<double>(), da, 1e-12);
    EXPECT_NE(out.value("singular", std::string()).find("spindle: first order: cos β = 0"), std::string::npos) << r.out;
    EXPECT_TRUE(out["nominal_after_mm"].contains("spindle") && out["nominal_after_mm"].contains("table"));

    // Only the table part: no d_beta_rad at all.
    json only_table = req;
    only_table.erase("spindle");
    const Proc r2 = run_solve("solve orientation", only_table.dump());
    ASSERT_EQ(r2.code, 0) << r2.err;
    const json out2 = json::parse(r2.out);
    EXPECT_FALSE(out2["exact"].contains("d_beta_rad"));
    EXPECT_TRUE(out2.at("singular").is_null());
}

TEST(CliSolve, SingularRrtttAnswersNullWithReason) {
    const json req{{"machine", "RRTTT"}, {"pivot_mm", {0, 0, 500}}, {"tool_ball_mm", {0, 0, -250}},
                   {"alpha_rad", 0.2},   {"beta_rad", M_PI / 2},    {"dV1_mm", {0, 0, 0}},
                   {"dV2_mm", {0, 0, 0}}};
    const Proc r = run_solve("solve orientation", req.dump());
    ASSERT_EQ(r.code, 0) << r.err;
    const json out = json::parse(r.out);
    EXPECT_TRUE(out["first_order"].is_null());
    EXPECT_TRUE(out["exact"].is_null());
    EXPECT_NE(out["singular"].get<std::string>().find("cos β = 0"), std::string::npos) << r.out;
}

TEST(CliSolve, MalformedRequestsNameTheField) {
    json bad_point = ssm_request({0, 0, 0});
    bad_point["points_mm"][2] = {1.0, 2.0};
    expect_field_error_solve(run_solve("solve ssm", bad_point.dump()), "points_mm[2]");

    json bad_number = ssm_request({0, 0, 0});
    bad_number["points_mm"][1][2] = "ten";
    expect_field_error_solve(run_solve("solve ssm", bad_number.dump()), "points_mm[1][2]");

    json missing = ssm_request({0, 0, 0});
    missing.erase("delta_l_mm");
    expect_field_error_solve(run_solve("solve ssm", missing.dump()), "delta_l_mm");

    json short_dl = ssm_request({0, 0, 0});
    short_dl["delta_l_mm"].erase(2);
    expect_field_error_solve(run_solve("solve ssm", short_dl.dump()), "delta_l_mm");

    json unknown = ssm_request({0, 0, 0});
    unknown["delta_l"] = 1;
    expect_field_error_solve(run_solve("solve ssm", unknown.dump()), "delta_l");

    json negative_std = ssm_request({0, 0, 0});
    negative_std["std_mm"] = -1;
    expect_field_error_solve(run_solve("solve ssm", negative_std.dump()), "std_mm");

    // A degenerate layout: all bars in one plane through the socket.
    const json planar{
        {"socket_mm", {0, 0, 0}}, {"points_mm", {{100, 0, 0}, {0, 100, 0}, {70, 70, 0}}}, {"delta_l_mm", {0, 0, 0}}};
    const Proc rp = run_solve("solve ssm", planar.dump());
    expect_field_error_solve(rp, "points_mm");
    EXPECT_NE(rp.err.find("condition number"), std::string::npos) << rp.err;

    const Proc not_json = run_solve("solve ssm", "{\"socket_mm\": [1, 2");
    EXPECT_EQ(not_json.code, 2);
    EXPECT_NE(json::parse(not_json.err).at("error").get<std::string>().find("malformed JSON"), std::string::npos);

    expect_field_error_solve(run_solve("solve orientation", R"({"machine":"XYZAB"})"), "machine");
    expect_field_error_solve(
        run_solve("solve orientation", R"({"machine":"RRTTT","pivot_mm":[0,0,0],"tool_ball_mm":[1,0,-250],
        "alpha_rad":0,"beta_rad":0,"dV1_mm":[0,0,0],"dV2_mm":[0,0,0]})"),
        "tool_ball_mm[0]");
    expect_field_error_solve(run_solve("solve orientation", R"({"machine":"RTTTR","spindle":{"pivot_mm":[0,0,0],
        "tool_ball_mm":[0,0,-250],"beta_rad":"x","dV1_mm":[0,0,0],"dV2_mm":[0,0,0]}})"),
                             "spindle.beta_rad");
    expect_field_error_solve(run_solve("solve orientation", R"({"machine":"RTTTR"})"), "spindle");
    expect_field_error_solve(
        run_solve("solve orientation", R"({"machine":"TTTRR","a_pivot_mm":[0,0,0],"c_offset_mm":[0,0,-100],
        "socket_mm":[1,2,3],"alpha_rad":0,"gamma_rad":0,"dV1_mm":[0,0,0]})"),
        "dV2_mm");

    const Proc no_file = run_solve("solve ssm --input /nonexistent/request.json");
    expect_field_error_solve(no_file, "--input");
}

TEST(CliSolve, HelpOnEverySubcommandAndUsage) {
    for (const char* args : {"solve --help", "solve ssm --help", "solve orientation --help"}) {
        const Proc r = run_solve(args);
        EXPECT_EQ(r.code, 0) << args << ": " << r.err;
        EXPECT_NE(r.out.find("solve"), std::string::npos) << args;
    }
    EXPECT_NE(run_solve("solve ssm --help").out.find("--input"), std::string::npos);
    EXPECT_NE(run_solve("solve orientation --help").out.find("TTTRR"), std::string::npos);
    EXPECT_EQ(run_solve("solve").code, 2) << "a subcommand is required";
}
