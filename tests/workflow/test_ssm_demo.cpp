// SPDX-License-Identifier: MIT
// The SSM demo as a use case, in process (workflow::run_ssm_demo): the emulator on a pty, the serial
// transport, the driver, the guided procedure, the database. For each machine type, and under the
// emulator's link faults, the measured total position errors match the emulator's true ones within 1 µm
// and the orientation errors within 2″ (0.1 µm bar noise), every stored point's window names the samples
// that made it, and every gap the link made is stored. The CLI's own test of `demo` checks its output
// and exit codes only (tests/app/test_cli_demo.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <tuple>

#include "ballbar/acquisition/result_codec.hpp"
#include "ballbar/analysis/types.hpp"
#include "ballbar/workflow/error.hpp"
#include "ballbar/workflow/ssm_demo.hpp"

namespace ballbar::workflow {
namespace {

namespace acq = ballbar::acquisition;
namespace ba = ballbar::analysis;

constexpr double kPositionTol_mm = 0.001;
constexpr double kAngleTol_rad = 2.0 / 3600.0 * ba::kPi / 180.0;

struct TempDb {
    std::filesystem::path dir;
    TempDb() {
        char tmpl[] = "/tmp/ballbar-workflow-XXXXXX";
        dir = ::mkdtemp(tmpl);
    }
    ~TempDb() { std::filesystem::remove_all(dir); }
    std::string file(const std::string& name) const { return (dir / name).string(); }
};

storage::StoreOptions fast() {
    storage::StoreOptions o;
    o.sync_full = false;
    return o;
}

/// Each measured location within 1 µm of the truth, each angle the test determines within 2″ and within
/// 5 of its stated uncertainty, which is not inflated (under 1″ for 0.1 µm of bar noise).
void expect_the_truth(const SsmDemoResult& r, ba::MachineType type) {
    ASSERT_EQ(r.locations.size(), 8u);  // four tests, two steps
    for (const auto& [m, truth] : r.locations) {
        EXPECT_LT((m.ssm.exact_mm - truth).norm(), kPositionTol_mm) << "test " << m.test << " step " << m.step;
        EXPECT_GT(truth.norm(), 0.005) << "errors are injected";
    }
    ASSERT_EQ(r.summary.tests.size(), 4u);
    for (const acq::TestResult& t : r.summary.tests) {
        const auto& truth = r.truth.at(static_cast<std::size_t>(t.test)).result.orientation.exact;
        ASSERT_TRUE(t.orientation.exact && t.std_rad && truth) << "test " << t.test;
        const ba::MeasuredAngles which = acq::measured_angles(type, t.kind);
        const std::tuple<bool, double ba::OrientationErrors::*, const char*> angles[] = {
            {which.alpha, &ba::OrientationErrors::d_alpha_rad, "Δα"},
            {which.beta, &ba::OrientationErrors::d_beta_rad, "Δβ"},
            {which.gamma, &ba::OrientationErrors::d_gamma_rad, "Δγ"}};
        for (const auto& [measured, member, name] : angles) {
            if (!measured) continue;
            const double err = (*t.orientation.exact).*member - (*truth).*member;
            const double u = (*t.std_rad).*member;
            EXPECT_NEAR(err, 0.0, kAngleTol_rad) << name << " test " << t.test;
            EXPECT_GT(u, 0.0) << name;
            EXPECT_LT(std::abs(err), 5 * u + 1e-9) << name << " test " << t.test;
            EXPECT_LT(u, ba::deg_to_rad(1.0 / 3600.0)) << name;
        }
    }
    EXPECT_EQ(r.check.wrong_pose, 0u) << r.check.first_wrong;
    EXPECT_EQ(r.check.stored_twice, 0u);
    EXPECT_EQ(r.check.points, r.plan.points.size());
}

/// Every stored point's window [first_seq, last_seq] holds exactly its n stored samples, and their mean
/// is the point's reading less one constant (the reference): the windows name the samples that made the
/// points, also after gaps in the stream and reconnects.
void expect_windows_name_their_samples(storage::Store& store, std::int64_t id) {
    std::map<std::uint64_t, double> displacement_mm;
    for (const auto& s : store.samples(id)) displacement_mm[s.seq] = s.displacement_nm * 1e-6;
    std::optional<double> offset_mm;
    for (const auto& p : store.points(id)) {
        ASSERT_TRUE(p.first_seq && p.last_seq);
        double sum = 0;
        int n = 0;
        for (auto it = displacement_mm.lower_bound(*p.first_seq);
             it != displacement_mm.end() && it->first <= *p.last_seq; ++it) {
            sum += it->second;
            ++n;
        }
        ASSERT_EQ(n, p.reading.n) << "location " << p.reading.location << " point " << p.reading.point;
        const double off = p.reading.measured_mm - sum / n;
        if (!offset_mm) offset_mm = off;
        EXPECT_NEAR(off, *offset_mm, 1e-6) << "location " << p.reading.location << " point " << p.reading.point;
    }
}

class SsmDemo : public ::testing::TestWithParam<ba::MachineType> {};

TEST_P(SsmDemo, RecoversTheEmulatorsErrorsThroughThePty) {
    TempDb dir;
    storage::Store store(dir.file("demo.db"), fast());
    SsmDemoOptions o;
    o.machine = GetParam();
    o.seed = 3;
    std::size_t progress_calls = 0;
    std::int64_t started_id = 0;
    SsmDemoEvents events;
    events.started = [&](std::int64_t id, const acq::Plan&, const std::string& pty) {
        started_id = id;
        EXPECT_EQ(pty.rfind("/dev/pts/", 0), 0u) << pty;
    };
    events.progress = [&](const acq::Progress&) { ++progress_calls; };
    const SsmDemoResult r = run_ssm_demo(store, o, events);
    EXPECT_EQ(started_id, r.session_id);
    EXPECT_GE(progress_calls, r.plan.points.size()) << "the front end hears every point";
    expect_the_truth(r, o.machine);
    EXPECT_EQ(store.session(r.session_id).state, storage::SessionState::completed);
    // What is stored is what the result holds: the results read back through their codec.
    std::size_t ssm = 0, orientation = 0;
    for (const auto& res : store.results(r.session_id)) {
        if (res.kind == acq::kSsmResultKind) ++ssm, (void)acq::location_from_json(res.payload_json);
        if (res.kind == acq::kOrientationResultKind) ++orientation, (void)acq::test_from_json(res.payload_json);
    }
    EXPECT_EQ(ssm, 8u);
    EXPECT_EQ(orientation, 4u);
    EXPECT_TRUE(store.sample_gaps(r.session_id).empty()) << "a clean link makes no gap";
    // A second demo is a second session.
    EXPECT_EQ(run_ssm_demo(store, o).session_id, r.session_id + 1);
}

INSTANTIATE_TEST_SUITE_P(AllTypes, SsmDemo,
                         ::testing::Values(ba::MachineType::RRTTT, ba::MachineType::TTTRR, ba::MachineType::RTTTR),
                         [](const auto& p) { return std::string(ba::to_string(p.param)); });

/// The same procedure under the emulator's faults, retry programs included.
class SsmDemoFaults : public ::testing::TestWithParam<std::tuple<ba::MachineType, bool>> {};

TEST_P(SsmDemoFaults, RecoversTheErrorsUnderFaults) {
    const auto [type, disconnect] = GetParam();
    TempDb dir;
    storage::Store store(dir.file("faults.db"), fast());
    SsmDemoOptions o;
    o.machine = type;
    o.seed = 4;
    if (disconnect) {
        o.faults.disconnect_at_s = 30;
        o.faults.disconnect_s = 8;
    } else {
        o.faults.drop_frame_probability = 0.03;
        o.faults.corrupt_byte_probability = 0.0005;
        o.faults.replay_frame_probability = 0.02;
        o.faults.start_delay_s = 20;
        o.faults.feed_override = 0.5;
    }
    const SsmDemoResult r = run_ssm_demo(store, o);
    expect_the_truth(r, type);
    if (disconnect) {
        EXPECT_EQ(r.summary.pauses, 1u);
        EXPECT_GE(r.summary.programs, 2u) << "a retry program";
    }
    // Every gap the link made is stored (issue 25): a dropped frame or one a corrupted byte voids makes a
    // gap (adjacent ones make one).
    const auto gaps = store.sample_gaps(r.session_id);
    if (!disconnect) {
        EXPECT_GT(gaps.size(), 0u);
        EXPECT_LE(gaps.size(), r.dropped_frames + r.corrupted_bytes);
    }
    expect_windows_name_their_samples(store, r.session_id);
}

INSTANTIATE_TEST_SUITE_P(AllTypes, SsmDemoFaults,
                         ::testing::Combine(::testing::Values(ba::MachineType::RRTTT, ba::MachineType::TTTRR,
                                                              ba::MachineType::RTTTR),
                                            ::testing::Bool()),
                         [](const auto& p) {
                             return std::string(ba::to_string(std::get<0>(p.param))) +
                                    (std::get<1>(p.param) ? "_Disconnect" : "_NoisyLink");
                         });

TEST(SsmDemo, AnUnfinishedSessionIsAFailureThatSaysHowItsPointsFared) {
    TempDb dir;
    storage::Store store(dir.file("refused.db"), fast());
    SsmDemoOptions o;
    o.plan = acq::default_plan(acq::seed_machine(o.machine));
    o.plan->answers.accept_results = false;  // the operator does not accept the results: aborted
    try {
        (void)run_ssm_demo(store, o);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.category(), ErrorCategory::failed);
        const std::string what = e.what();
        EXPECT_NE(what.find("ended aborted"), std::string::npos) << what;
        EXPECT_NE(what.find("checked against the truth: all at their pose"), std::string::npos) << what;
    }
}

}  // namespace
}  // namespace ballbar::workflow
