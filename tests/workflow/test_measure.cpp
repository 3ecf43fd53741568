// SPDX-License-Identifier: MIT
// The SSM measurement as a use case, in process: a new session on the emulator (`emulator:` with a
// configuration whose machine runs the program the operator writes), a run stopped half-way by the front
// end's stop flag and taken up again from its stored plan and points, and the refusals of a resume.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "../scratch_dir.hpp"
#include "ballbar/acquisition/machine_file.hpp"
#include "ballbar/acquisition/result_codec.hpp"
#include "ballbar/analysis/nc_program.hpp"
#include "ballbar/device/pipe.hpp"
#include "ballbar/report/build.hpp"
#include "ballbar/report/report.hpp"
#include "ballbar/workflow/error.hpp"
#include "ballbar/workflow/measure.hpp"

namespace ballbar::workflow {
namespace {

namespace acq = ballbar::acquisition;
namespace fs = std::filesystem;
const fs::path kData = fs::path(BALLBAR_TEST_DATA_DIR) / "machines";

std::string slurp(const fs::path& p) {
    std::ifstream f(p);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

/// A scratch directory that also writes the emulator's configuration.
struct Dir : ballbar::test::ScratchDir {
    Dir() : ScratchDir("measure-wf") {}
    /// An `emulator:` URI whose machine runs the program written to `program` (at each cycle start).
    std::string device(const fs::path& program) const { return "emulator:" + config(program).string(); }
    fs::path config(const fs::path& program) const {
        std::string cfg = slurp(kData / "tttrr-emulator.json");
        cfg.replace(cfg.find("PROGRAM"), 7, program.string());
        const fs::path p = path / ("emulator-" + program.stem().string() + ".json");
        std::ofstream(p) << cfg;
        return p;
    }
};

/// The plan's answers, and the machine's operator: writes each program where the emulated machine loads
/// it. Sets `stop` once `stop_after` points are captured (a front end's stop button).
class FileOperator : public acq::ScriptedOperator {
  public:
    FileOperator(const acq::Plan& plan, fs::path program, std::atomic<bool>* stop = nullptr, std::size_t stop_after = 0)
        : acq::ScriptedOperator(plan.spec.answers),
          program_(std::move(program)),
          stop_(stop),
          stop_after_(stop_after) {}
    void run_program(const analysis::NcProgram& program, std::span<const std::size_t> points, bool retry) override {
        std::ofstream(program_) << analysis::write_nc_program(program, "test");
        last_program_points = points.size();
        retried = retried || retry;
    }
    void progress(const acq::Progress& p) override {
        if (stop_ && stop_after_ > 0 && p.done >= stop_after_) stop_->store(true);
    }
    std::size_t last_program_points = 0;
    bool retried = false;

  private:
    fs::path program_;
    std::atomic<bool>* stop_;
    std::size_t stop_after_;
};

/// The run's options: the emulator of `config` in process, on simulated time (a run takes what the CPU
/// needs, not the machine's minutes); `device_uri` as a front end would give it.
SsmMeasureOptions simulated(const Dir& d, const fs::path& program) {
    SsmMeasureOptions o;
    o.device_uri = d.device(program);
    const fs::path cfg = d.config(program);
    o.open_transport = [cfg] {
        return std::make_unique<device::PipeTransport>(
            std::make_unique<device::Emulator>(device::load_emulator_config(cfg.string())), device::Pacing::Simulated);
    };
    return o;
}

acq::Plan quick_plan() {
    const acq::MachineFile m = acq::parse_machine_file(slurp(kData / "tttrr.json"));
    return acq::make_plan(m, acq::parse_plan_file(slurp(kData / "tttrr-quick.plan.json"), m.geometry.type));
}

TEST(MeasureUseCase, ANewSessionIsMeasuredAndStoredCompleted) {
    Dir d;
    storage::Store store((d.path / "m.db").string());
    const fs::path program = d.path / "a.nc";
    const std::string device = d.device(program);
    const PreparedSession s = new_ssm_session(store, quick_plan(), device);
    EXPECT_EQ(store.session(s.id).source, storage::SessionSource::emulator);
    FileOperator op(s.plan, program);
    const SsmMeasureOptions o = simulated(d, program);
    const acq::SessionSummary sum = measure_ssm(store, s, op, o);
    ASSERT_EQ(sum.final_state, acq::State::Done) << sum.reason;
    EXPECT_EQ(store.session(s.id).state, storage::SessionState::completed);
    EXPECT_EQ(store.points(s.id).size(), s.plan.points.size());
    const auto instrument = store.session(s.id).instrument;
    ASSERT_TRUE(instrument.has_value()) << "the instrument's identity is stored";
    EXPECT_FALSE(instrument->serial.empty());
    std::size_t orientation = 0;
    for (const auto& r : store.results(s.id))
        if (r.kind == acq::kOrientationResultKind) ++orientation, (void)acq::test_from_json(r.payload_json);
    EXPECT_EQ(orientation, static_cast<std::size_t>(s.plan.test_count()));
    // A completed session is not taken up again, and nothing changes.
    try {
        (void)resume_ssm_session(store, std::to_string(s.id));
        FAIL() << "resumed a completed session";
    } catch (const Error& e) {
        EXPECT_EQ(e.category(), ErrorCategory::bad_input) << e.what();
    }
    EXPECT_EQ(store.session(s.id).state, storage::SessionState::completed);
}

/// Keeps the review question's text (the results and the verdict the operator accepts).
class ReviewingOperator : public FileOperator {
  public:
    using FileOperator::FileOperator;
    std::size_t choose(const acq::Choice& c) override {
        if (c.what == "review") review = c.prompt;
        return FileOperator::choose(c);
    }
    std::string review;
};

TEST(MeasureUseCase, TheMachineFilesTolerancesAreJudgedAtTheReviewAndReachTheReport) {
    Dir d;
    storage::Store store((d.path / "m.db").string());
    const fs::path program = d.path / "a.nc";
    acq::MachineFile m = acq::parse_machine_file(slurp(kData / "tttrr.json"));
    // Tolerances between the emulator's errors: some figures pass, some fail. Written to the file and read
    // back, as an operator's machine file would be.
    m.tolerances.location_um = 30;
    m.tolerances.angle_arcsec = 50;
    m = acq::parse_machine_file(acq::write_machine_file(m));
    ASSERT_EQ(m.tolerances.location_um, 30.0);
    const acq::Plan plan =
        acq::make_plan(m, acq::parse_plan_file(slurp(kData / "tttrr-quick.plan.json"), m.geometry.type));
    const PreparedSession s = new_ssm_session(store, plan, d.device(program));
    ReviewingOperator op(s.plan, program);
    const acq::SessionSummary sum = measure_ssm(store, s, op, simulated(d, program));
    ASSERT_EQ(sum.final_state, acq::State::Done) << sum.reason;

    // The judgement, recomputed here from the stored results alone: |ΔV| ≤ 30 µm, |exact angle| ≤ 50″.
    std::size_t checked = 0, failed = 0, angles_failed = 0;
    for (const auto& r : store.results(s.id)) {
        if (r.kind == acq::kSsmResultKind) {
            const acq::LocationResult l = acq::location_from_json(r.payload_json);
            ++checked;
            failed += l.dV_mm.norm() * 1e3 > 30 ? 1 : 0;
        } else if (r.kind == acq::kOrientationResultKind) {
            const acq::TestResult t = acq::test_from_json(r.payload_json);
            ASSERT_TRUE(t.orientation.exact.has_value());
            const auto angles = acq::measured_angles(m.geometry.type, t.kind);
            const auto& e = *t.orientation.exact;
            for (auto [on, rad] : {std::pair{angles.alpha, e.d_alpha_rad}, std::pair{angles.beta, e.d_beta_rad},
                                   std::pair{angles.gamma, e.d_gamma_rad}})
                if (on) ++checked, angles_failed += std::abs(analysis::rad_to_arcsec(rad)) > 50 ? 1 : 0;
        }
    }
    failed += angles_failed;
    ASSERT_GT(failed, 0u);
    ASSERT_LT(failed, checked);  // both verdicts exercised
    const std::string expected = "FAIL: " + std::to_string(failed) + " of " + std::to_string(checked);
    EXPECT_NE(op.review.find(expected), std::string::npos) << op.review;

    // The report reads the tolerances from the stored plan: the same verdict at its top and in its JSON.
    const report::Report r = report::build_report(store, s.id);
    const report::SsmVerdict v = report::ssm_verdict(r);
    EXPECT_TRUE(v.judged);
    EXPECT_FALSE(v.pass);
    EXPECT_EQ(v.checked, checked);
    EXPECT_EQ(v.failures.size(), failed);
    const auto j = report::to_json(r);
    EXPECT_EQ(j["ssm_verdict"]["location_tolerance_um"], 30.0);
    EXPECT_EQ(j["ssm_verdict"]["angle_tolerance_arcsec"], 50.0);
    EXPECT_FALSE(j["ssm_verdict"]["pass"].get<bool>());
    // A tolerance given at report time replaces the file's; the other stays.
    report::Report given = r;
    report::set_ssm_tolerances(given, 1000.0, std::nullopt);
    EXPECT_EQ(given.location_tolerance_source, "given");
    EXPECT_EQ(given.angle_tolerance_arcsec, 50.0);
    EXPECT_EQ(report::ssm_verdict(given).failures.size(), angles_failed);
}

TEST(MeasureUseCase, APlanTestsOwnTolerancesReplaceTheMachinesForThatTestAtTheReviewAndInTheReport) {
    Dir d;
    storage::Store store((d.path / "m.db").string());
    const fs::path program = d.path / "t.nc";
    acq::MachineFile m = acq::parse_machine_file(slurp(kData / "tttrr.json"));
    m.tolerances.location_um = 1;  // every location fails the machine's…
    m.tolerances.angle_arcsec = 1;
    acq::PlanSpec spec = acq::parse_plan_file(slurp(kData / "tttrr-quick.plan.json"), m.geometry.type);
    spec.tests.push_back(spec.tests[0]);  // a second test at the same socket, C turned the other way
    spec.tests[1].second_rad = -spec.tests[1].second_rad;
    spec.tests[0].tolerances.location_um = 5000;  // …but the first test has lenient ones of its own
    spec.tests[0].tolerances.angle_arcsec = 30000;
    spec = acq::parse_plan_file(acq::write_plan_file(spec, m.geometry.type), m.geometry.type);  // as a file would
    const PreparedSession s = new_ssm_session(store, acq::make_plan(m, spec), d.device(program));
    ReviewingOperator op(s.plan, program);
    const acq::SessionSummary sum = measure_ssm(store, s, op, simulated(d, program));
    ASSERT_EQ(sum.final_state, acq::State::Done) << sum.reason;

    // Recomputed from the stored results: the first test's figures pass, every other test's fail.
    std::size_t checked = 0, failed = 0;
    for (const auto& r : store.results(s.id)) {
        if (r.kind == acq::kSsmResultKind) {
            const acq::LocationResult l = acq::location_from_json(r.payload_json);
            ++checked;
            failed += l.dV_mm.norm() * 1e3 > (l.test == 0 ? 5000 : 1) ? 1 : 0;
        } else if (r.kind == acq::kOrientationResultKind) {
            const acq::TestResult t = acq::test_from_json(r.payload_json);
            ASSERT_TRUE(t.orientation.exact.has_value());
            const auto angles = acq::measured_angles(m.geometry.type, t.kind);
            const auto& e = *t.orientation.exact;
            for (auto [on, rad] : {std::pair{angles.alpha, e.d_alpha_rad}, std::pair{angles.beta, e.d_beta_rad},
                                   std::pair{angles.gamma, e.d_gamma_rad}})
                if (on) ++checked, failed += std::abs(analysis::rad_to_arcsec(rad)) > (t.test == 0 ? 30000 : 1) ? 1 : 0;
        }
    }
    ASSERT_GT(failed, 0u);
    ASSERT_LT(failed, checked);
    EXPECT_NE(op.review.find("FAIL: " + std::to_string(failed) + " of " + std::to_string(checked)), std::string::npos)
        << op.review;
    EXPECT_EQ(op.review.find("test 1 "), std::string::npos) << "the first test judged by the machine's: " << op.review;

    const report::Report r = report::build_report(store, s.id);
    const report::SsmVerdict v = report::ssm_verdict(r);
    EXPECT_EQ(v.checked, checked);
    EXPECT_EQ(v.failures.size(), failed);
    const auto j = report::to_json(r);
    EXPECT_EQ(j["locations"][0]["tolerance_um"], 5000.0);
    EXPECT_EQ(j["locations"][2]["tolerance_um"], 1.0);
    EXPECT_EQ(r.location_tolerance_source,
              "the machine file, stored with the session; test 1 its own, from the plan stored with the session");
    // A tolerance given at report time is for every test.
    report::Report given = r;
    report::set_ssm_tolerances(given, 1.0, 1.0);
    EXPECT_EQ(report::ssm_verdict(given).failures.size(), checked);
}

TEST(MeasureUseCase, AStoppedRunIsTakenUpAfterItsLastPoint) {
    Dir d;
    storage::Store store((d.path / "m.db").string());
    const fs::path program = d.path / "b.nc";
    const std::string device = d.device(program);
    const PreparedSession s = new_ssm_session(store, quick_plan(), device);
    std::atomic<bool> stop{false};
    FileOperator op(s.plan, program, &stop, 3);
    SsmMeasureOptions o = simulated(d, program);
    o.stop = &stop;
    const acq::SessionSummary first = measure_ssm(store, s, op, o);
    ASSERT_TRUE(first.interrupted) << first.reason;
    EXPECT_EQ(store.session(s.id).state, storage::SessionState::interrupted);
    const std::size_t kept = store.points(s.id).size();
    ASSERT_GE(kept, 3u);
    ASSERT_LT(kept, s.plan.points.size());

    const PreparedSession again = resume_ssm_session(store, std::to_string(s.id));
    EXPECT_EQ(again.done.size(), kept);
    ASSERT_TRUE(again.before.has_value());
    EXPECT_EQ(again.before->state, storage::SessionState::interrupted);
    EXPECT_EQ(again.plan.points.size(), s.plan.points.size()) << "the stored plan";
    const fs::path program2 = d.path / "b2.nc";
    FileOperator op2(again.plan, program2);
    o = simulated(d, program2);
    const acq::SessionSummary second = measure_ssm(store, again, op2, o);
    ASSERT_EQ(second.final_state, acq::State::Done) << second.reason;
    EXPECT_EQ(op2.last_program_points, s.plan.points.size() - kept) << "only the missing points are measured";
    EXPECT_EQ(store.session(s.id).state, storage::SessionState::completed);
}

TEST(MeasureUseCase, ASessionThatDoesNotExistIsNotFound) {
    Dir d;
    storage::Store store((d.path / "m.db").string());
    try {
        (void)resume_ssm_session(store, "42");
        FAIL() << "no error";
    } catch (const std::exception& e) {
        EXPECT_EQ(category_of(e), ErrorCategory::not_found) << e.what();
    }
}

}  // namespace
}  // namespace ballbar::workflow
