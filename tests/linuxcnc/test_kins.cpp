// SPDX-License-Identifier: MIT
// The ballbarkins module's kinematics in process (CompensatingKins), checked against what the
// library did not make: LinuxCNC's xyzac-trt-kins equations (src/emc/kinematics/trtfuncs.c of the
// LinuxCNC that Debian 12 ships, written out here) and the independent erroneous machine of
// tests/independent_tttrr.hpp.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <new>
#include <random>
#include <string>

#include "../independent_tttrr.hpp"
#include "../scratch_dir.hpp"
#include "ballbar/linuxcnc/kins.hpp"

namespace {

namespace tt = ballbar::test::tttrr;
namespace bl = ballbar::linuxcnc;
namespace ba = ballbar::analysis;

std::atomic<long> g_allocations{0};

const tt::Geometry kGeometry{{0, 20, 10}, {0, -20, -110}};

ba::MachineGeometry geometry() {
    ba::MachineGeometry g;
    g.type = ba::MachineType::TTTRR;
    g.a_pivot_mm = {kGeometry.a_pivot.x, kGeometry.a_pivot.y, kGeometry.a_pivot.z};
    g.c_offset_mm = {kGeometry.c_offset.x, kGeometry.c_offset.y, kGeometry.c_offset.z};
    return g;
}

ba::ErrorParams params(const tt::Errors& e) {
    ba::ErrorParams p;
    p[ba::Param::Y0A] = e.Y0A, p[ba::Param::Z0A] = e.Z0A, p[ba::Param::B0A] = e.B0A, p[ba::Param::C0A] = e.C0A;
    p[ba::Param::X0C] = e.X0C, p[ba::Param::Y0C] = e.Y0C, p[ba::Param::A0C] = e.A0C, p[ba::Param::B0C] = e.B0C;
    p[ba::Param::A_zero] = e.A_zero, p[ba::Param::C_zero] = e.C_zero, p[ba::Param::EXX] = e.EXX;
    p[ba::Param::EYY] = e.EYY, p[ba::Param::C0Y] = e.C0Y;
    return p;
}

// LinuxCNC 2.9's xyzacKinematicsInverse/Forward (trtfuncs.c), with its pins' values.
struct Trt {
    double xr, yr, zr, dy, dz;
};
bl::Axes trt_inverse(const Trt& k, const bl::Axes& p, double dt) {
    const double a = tt::rad(p[3]), c = tt::rad(p[4]), dz = k.dz + dt, dy = k.dy;
    const double x = p[0] - k.xr, y = p[1] - k.yr, z = p[2] - k.zr;
    return {std::cos(c) * x - std::sin(c) * y + k.xr,
            std::sin(c) * std::cos(a) * x + std::cos(c) * std::cos(a) * y - std::sin(a) * z - std::cos(a) * dy +
                std::sin(a) * dz + dy + k.yr,
            std::sin(c) * std::sin(a) * x + std::cos(c) * std::sin(a) * y + std::cos(a) * z - std::sin(a) * dy -
                std::cos(a) * dz + dz + k.zr,
            p[3], p[4]};
}
bl::Axes trt_forward(const Trt& k, const bl::Axes& j, double dt) {
    const double a = tt::rad(j[3]), c = tt::rad(j[4]), dz = k.dz + dt, dy = k.dy;
    const double x = j[0] - k.xr, y = j[1] - dy - k.yr, z = j[2] - dz - k.zr;
    return {std::cos(c) * x + std::sin(c) * std::cos(a) * y + std::sin(c) * std::sin(a) * z + std::sin(c) * dy + k.xr,
            -std::sin(c) * x + std::cos(c) * std::cos(a) * y + std::cos(c) * std::sin(a) * z + std::cos(c) * dy + k.yr,
            -std::sin(a) * y + std::cos(a) * z + dz + k.zr, j[3], j[4]};
}

bl::Axes random_world(std::mt19937& rng) {
    std::uniform_real_distribution<double> lin(-150, 150), a(-95, 95), c(-400, 400);
    return {lin(rng), lin(rng), lin(rng), a(rng), c(rng)};
}

TEST(LinuxcncKins, AZeroErrorModelIsLinuxcncsXyzacTrtKinsInBothDirections) {
    const bl::CompensatingKins k(geometry(), ba::ErrorParams{});
    const auto s = k.xyzac_equivalent();
    const Trt trt{s.x_rot_point, s.y_rot_point, s.z_rot_point, s.y_offset, s.z_offset};
    EXPECT_DOUBLE_EQ(s.y_rot_point, 0.0);  // a_pivot + c_offset
    EXPECT_DOUBLE_EQ(s.z_rot_point, -100.0);
    EXPECT_DOUBLE_EQ(s.y_offset, 20.0);  // −c_offset
    EXPECT_DOUBLE_EQ(s.z_offset, 110.0);
    std::mt19937 rng(7);
    for (int i = 0; i < 500; ++i) {
        const bl::Axes w = random_world(rng);
        const double dt = i % 3 == 0 ? 0.0 : 37.5 * (i % 5);
        const auto inv = k.inverse(bl::KinsType::tcp, w, dt, true);
        const bl::Axes want = trt_inverse(trt, w, dt);
        for (std::size_t j = 0; j < 5; ++j) ASSERT_NEAR(inv.joints[j], want[j], 1e-9) << "joint " << j << " pose " << i;
        const bl::Axes fw = k.forward(bl::KinsType::tcp, inv.joints, dt, true);
        const bl::Axes trt_fw = trt_forward(trt, inv.joints, dt);
        for (std::size_t j = 0; j < 5; ++j) {
            ASSERT_NEAR(fw[j], w[j], 1e-9);
            ASSERT_NEAR(trt_fw[j], w[j], 1e-9);  // the equations above are LinuxCNC's pair
        }
        // Identity: the joints are the axis words (the zero model's correction is rounding, 1e-15).
        const auto id = k.inverse(bl::KinsType::identity, w, dt, true);
        for (std::size_t j = 0; j < 5; ++j) ASSERT_NEAR(id.joints[j], w[j], 1e-12);
    }
}

// At every pose, the commanded joints run through the erroneous machine put the tool tip on the
// table point (and along the tool axis) the world position names on the nominal machine, within
// the first-order remainder; without the correction the tool misses by tens of µm.
TEST(LinuxcncKins, TheCorrectedJointsPutTheToolOnTheIntendedTablePoint) {
    const tt::Errors e = tt::seed_like();
    const bl::CompensatingKins k(geometry(), params(e));
    std::mt19937 rng(11);
    double worst_on = 0, worst_off = 0, worst_axis = 0;
    int singular = 0;
    for (int i = 0; i < 2000; ++i) {
        const bl::Axes w = random_world(rng);
        const double dt = i % 2 ? 0.0 : 60.0;
        const tt::V tool{0, 0, -dt};
        const tt::V tip_world{w[0], w[1], w[2] - dt};
        const tt::V intended = tt::table_point(kGeometry, tip_world);
        const tt::V intended_axis = tt::rot_z(-tt::rad(w[4]), tt::rot_x(-tt::rad(w[3]), {0, 0, 1}));
        for (const bool on : {true, false}) {
            const auto r = k.inverse(bl::KinsType::tcp, w, dt, on);
            const tt::Seen s = tt::actual_tool_in_table(kGeometry, e, r.joints[0], r.joints[1], r.joints[2],
                                                        tt::rad(r.joints[3]), tt::rad(r.joints[4]), tool);
            const double miss = tt::norm(s.position - intended);
            if (on) {
                singular += r.singular;
                worst_on = std::max(worst_on, miss);
                if (!r.singular) worst_axis = std::max(worst_axis, tt::norm(tt::cross(s.axis, intended_axis)));
            } else {
                worst_off = std::max(worst_off, miss);
            }
        }
    }
    RecordProperty("worst_miss_um", std::to_string(worst_on * 1e3));
    EXPECT_LT(worst_on, 0.5e-3);  // first-order remainder: |dθ|²·lever + |e|·|dv|, well under 0.5 µm
    EXPECT_LT(worst_axis, 1e-6);  // 0.2″: second order, largest where C turns most (A of a few degrees)
    EXPECT_GT(worst_off, 20e-3);  // the errors are there: uncorrected, tens of µm
    // C not corrected within 0.06° of A = 0, or where it would have to turn more than 0.1° in one step
    // (|A| below about 1.7° for these errors): under 2 % of the random poses.
    EXPECT_LT(singular, 60);
}

TEST(LinuxcncKins, InIdentityTypeTheAxisWordsAreTheNominalJoints) {
    const tt::Errors e = tt::seed_like();
    const bl::CompensatingKins k(geometry(), params(e));
    std::mt19937 rng(3);
    for (int i = 0; i < 200; ++i) {
        const bl::Axes u = random_world(rng);
        const auto r = k.inverse(bl::KinsType::identity, u, 0.0, true);
        // The tool tip of the corrected joints on the erroneous machine is where the nominal machine
        // puts it at the axis words u.
        const tt::V nominal = tt::table_point(
            kGeometry,
            tt::rot_z(-tt::rad(u[4]),
                      tt::rot_x(-tt::rad(u[3]), tt::V{u[0], u[1], u[2]} - kGeometry.a_pivot) - kGeometry.c_offset) +
                kGeometry.a_pivot + kGeometry.c_offset);
        const tt::Seen s = tt::actual_tool_in_table(kGeometry, e, r.joints[0], r.joints[1], r.joints[2],
                                                    tt::rad(r.joints[3]), tt::rad(r.joints[4]), {0, 0, 0});
        if (!r.singular) {
            ASSERT_LT(tt::norm(s.position - nominal), 0.5e-3) << i;
        }
        const bl::Axes back = k.forward(bl::KinsType::identity, r.joints, 0.0, true);
        for (std::size_t j = 0; j < 5; ++j) ASSERT_NEAR(back[j], u[j], 1e-9);
        const auto off = k.inverse(bl::KinsType::identity, u, 0.0, false);
        for (std::size_t j = 0; j < 5; ++j) ASSERT_EQ(off.joints[j], u[j]);
    }
}

TEST(LinuxcncKins, ForwardInvertsTheCorrectedInverse) {
    const bl::CompensatingKins k(geometry(), params(tt::seed_like()));
    std::mt19937 rng(5);
    for (int i = 0; i < 500; ++i) {
        const bl::Axes w = random_world(rng);
        for (const auto type : {bl::KinsType::tcp, bl::KinsType::identity}) {
            const auto r = k.inverse(type, w, 25.0, true);
            const bl::Axes back = k.forward(type, r.joints, 25.0, true);
            for (std::size_t j = 0; j < 5; ++j) ASSERT_NEAR(back[j], w[j], 1e-9) << "pose " << i << " joint " << j;
        }
    }
}

TEST(LinuxcncKins, TheServoCyclePathAllocatesNothing) {
    const bl::CompensatingKins k(geometry(), params(tt::seed_like()));
    std::mt19937 rng(9);
    std::vector<bl::Axes> poses;
    for (int i = 0; i < 100; ++i) poses.push_back(random_world(rng));
    const long before = g_allocations.load();
    double sink = 0;
    for (const auto& w : poses) {
        sink += k.inverse(bl::KinsType::tcp, w, 10.0, true).joints[0];
        sink += k.forward(bl::KinsType::tcp, w, 10.0, true)[1];
    }
    EXPECT_EQ(g_allocations.load() - before, 0);
    EXPECT_TRUE(std::isfinite(sink));
}

TEST(LinuxcncKins, AModelThatCannotBeUsedIsRefusedWithItsReason) {
    const ballbar::test::ScratchDir d("kins");
    auto refusal = [](const std::string& path) {
        try {
            (void)bl::CompensatingKins::from_model_file(path);
        } catch (const bl::KinsLoadError& e) {
            return std::string(e.what());
        }
        return std::string("loaded");
    };
    EXPECT_EQ(refusal((d.path / "absent.json").string()),
              "cannot open the model file '" + (d.path / "absent.json").string() + "'");
    const std::string bad = d.write("bad.json", R"({"format":"ballbar-model/1","machine":)");
    EXPECT_NE(refusal(bad).find("is not a ballbar-model/1"), std::string::npos) << refusal(bad);
    const std::string unknown = d.write(
        "unknown.json",
        R"({"format":"ballbar-model/1","machine":{"type":"TTTRR","a_pivot_mm":[0,0,0],"c_offset_mm":[0,0,-100],"tool_ball_mm":[0,0,0]},"params":{"QQQ":1}})");
    EXPECT_NE(refusal(unknown).find("QQQ"), std::string::npos) << refusal(unknown);
    const std::string head = d.write(
        "head.json",
        R"({"format":"ballbar-model/1","machine":{"type":"RRTTT","a_pivot_mm":[0,0,0],"c_offset_mm":[0,0,0],"tool_ball_mm":[0,0,-250]},"params":{}})");
    EXPECT_NE(refusal(head).find("TTTRR"), std::string::npos) << refusal(head);
    const std::string good = d.write(
        "good.json",
        R"({"format":"ballbar-model/1","machine":{"type":"TTTRR","a_pivot_mm":[0,20,10],"c_offset_mm":[0,-20,-110],"tool_ball_mm":[0,0,0]},"params":{"Y0A":0.025}})");
    const auto k = bl::CompensatingKins::from_model_file(good);
    std::ifstream in(good);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(k.model_hash(), bl::fnv1a(text));
    EXPECT_EQ(bl::fnv1a(""), 2166136261u);   // FNV-1a's offset basis
    EXPECT_EQ(bl::fnv1a("a"), 0xe40c292cu);  // its published test vector
}

}  // namespace

// Counts every allocation of the test program (the servo-cycle test reads it): operator new replaced,
// on malloc and free. GCC takes the pairing of a replaced new with free for a mismatch.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
void* operator new(std::size_t n) {
    g_allocations.fetch_add(1, std::memory_order_relaxed);
    if (void* p = std::malloc(n ? n : 1)) return p;
    throw std::bad_alloc();
}
void operator delete(void* p) noexcept {
    std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
    std::free(p);
}
