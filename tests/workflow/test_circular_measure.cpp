// SPDX-License-Identifier: MIT
// The circular test's measurement as a use case, in process: the emulated machine (its continuous errors)
// and instrument on simulated time, the part program written where the machine loads it; a completed
// session with its analysed result stored, a run stopped by the front end's flag and taken up again, and
// the refusals of a resume.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "../scratch_dir.hpp"
#include "ballbar/acquisition/circle_program.hpp"
#include "ballbar/acquisition/machine_file.hpp"
#include "ballbar/device/emulator.hpp"
#include "ballbar/device/pipe.hpp"
#include "ballbar/storage/trace_file.hpp"
#include "ballbar/workflow/circular_measure.hpp"
#include "ballbar/workflow/circular_test.hpp"
#include "ballbar/workflow/error.hpp"
#include "ballbar/workflow/import_export.hpp"

namespace ballbar::workflow {
namespace {

namespace acq = ballbar::acquisition;
namespace circ = ballbar::analysis::circular;
namespace fs = std::filesystem;

/// An XY test of R 100 mm at 1000 mm/min, both directions, feed-in 0.8 mm (the bar's ±1 mm range).
circ::TestSpec xy_test() {
    return storage::parse_test_json(
        R"({"kind": "circular", "plane": "XY", "radius_mm": 100.0, "centre_mm": [0, 0, 0], "feed_mm_min": 1000.0,
            "feed_in_mm": 0.8, "runs": [{"direction": "ccw", "start_deg": 0, "overshoot_deg": 45, "data_arc_deg": 360},
                                        {"direction": "cw", "start_deg": 450, "overshoot_deg": 45, "data_arc_deg": 360}]})");
}

/// The emulated machine with 3 µm of X backlash and 25 µm/m of XY squareness, standing at the test's
/// start (R + feed-in on +X), running the program at `program` when told to start.
fs::path emulator_config(const ballbar::test::ScratchDir& d, const fs::path& program) {
    const fs::path p = d.path / "emulator.json";
    std::ofstream(p)
        << R"({"time": "simulated", "seed": 5, "instrument": {"calibrated_length_mm": 100, "noise_um": 0.15},
        "machine": {"start": {"X_mm": 100.8, "Y_mm": 0, "Z_mm": 0}},
        "program": {"file": ")"
        << program.string() << R"(", "start": "cycle_start"},
        "continuous": {"servo_lag_ms": {"X": 8, "Y": 5}, "backlash_um": {"X": 3},
                       "squareness_um_per_m": {"XY": 25}}})";
    return p;
}

/// Answers yes, and writes the part program where the machine loads it when told to run it. Sets `stop`
/// once `stop_after_runs` runs were started (a front end's stop button).
class ProgramOperator : public acq::Operator {
  public:
    ProgramOperator(fs::path path, std::string program, std::atomic<bool>* stop = nullptr, int stop_after_runs = 0)
        : path_(std::move(path)), program_(std::move(program)), stop_(stop), stop_after_(stop_after_runs) {}
    bool confirm(std::string_view, std::string_view) override { return true; }
    std::size_t choose(const acq::Choice& c) override { return c.default_option; }
    void message(std::string_view) override {}
    acq::PointFailureAction point_failed(const acq::CapturedPoint&, std::string_view) override {
        return acq::PointFailureAction::Abort;
    }
    void wait_at_point(const acq::PlannedPoint&) override {}
    void progress(const acq::Progress&) override {}
    void run_program(const analysis::NcProgram&, std::span<const std::size_t>, bool) override {}
    void program_stop(const acq::ProgramStop&) override {}
    void run_part_program(std::string_view, bool) override {
        std::ofstream(path_) << program_;
        ++runs;
        if (stop_ && stop_after_ > 0 && runs >= stop_after_) stop_->store(true);
    }
    int runs = 0;

  private:
    fs::path path_;
    std::string program_;
    std::atomic<bool>* stop_;
    int stop_after_;
};

CircularMeasureOptions simulated_circular_measure(const fs::path& config) {
    CircularMeasureOptions o;
    o.device_uri = "emulator:" + config.string();
    o.open_transport = [config] {
        return std::make_unique<device::PipeTransport>(
            std::make_unique<device::Emulator>(device::load_emulator_config(config.string())),
            device::Pacing::Simulated);
    };
    return o;
}

double diagnostic(const std::string& payload, const std::string& key) {
    const nlohmann::json result = nlohmann::json::parse(payload);  // outlives the loop over its list
    for (const auto& d : result.at("diagnostics"))
        if (d.at("key").get<std::string>() == key) return d.at("value").get<double>();
    ADD_FAILURE() << key << " not in " << payload;
    return 0;
}

TEST(CircularMeasureUseCase, ANewSessionIsMeasuredAnalysedAndStored) {
    ballbar::test::ScratchDir d{"circular-wf"};
    storage::Store store((d.path / "c.db").string());
    const fs::path program = d.path / "circle.nc";
    PreparedCircular p;
    p.test = xy_test();
    ProgramOperator op(program, acq::circular_program(p.test, p.dialect, p.dwell_s));
    CircularMeasureOptions o = simulated_circular_measure(emulator_config(d, program));
    std::optional<std::int64_t> created;
    o.on_session_created = [&created](std::int64_t id, const circ::TestSpec&) { created = id; };
    const CircularMeasureResult r = measure_circular(store, p, op, o);
    ASSERT_EQ(r.summary.final_state, acq::State::Done) << r.summary.reason;
    ASSERT_TRUE(r.session_id.has_value());
    EXPECT_EQ(created, r.session_id) << "the front end hears of the session when it is made";
    EXPECT_EQ(store.session(*r.session_id).state, storage::SessionState::completed);
    EXPECT_EQ(store.session(*r.session_id).source, storage::SessionSource::emulator);
    ASSERT_TRUE(r.stored.has_value());
    EXPECT_NEAR(diagnostic(r.stored->payload_json, "backlash_x_um"), 3.0, 0.6);
    EXPECT_NEAR(diagnostic(r.stored->payload_json, "squareness_um_per_m"), 25.0, 5.0);
    int circular = 0;
    for (const auto& res : store.results(*r.session_id)) circular += res.kind == "circular";
    EXPECT_EQ(circular, 1) << "the analysed result is stored once";
    EXPECT_NO_THROW(throw_unless_completed(r.summary, r.session_id, "-"));
    // A completed session is not taken up again, and nothing changes.
    try {
        (void)resume_circular_session(store, std::to_string(*r.session_id));
        FAIL() << "resumed a completed session";
    } catch (const Error& e) {
        EXPECT_EQ(e.category(), ErrorCategory::bad_input) << e.what();
    }
    EXPECT_EQ(store.session(*r.session_id).state, storage::SessionState::completed);
}

TEST(CircularMeasureUseCase, AStoppedRunIsTakenUpAndCompleted) {
    ballbar::test::ScratchDir d{"circular-wf"};
    storage::Store store((d.path / "c.db").string());
    const fs::path program = d.path / "circle.nc";
    PreparedCircular p;
    p.test = xy_test();
    std::atomic<bool> stop{false};
    ProgramOperator op(program, acq::circular_program(p.test, p.dialect, p.dwell_s), &stop, 1);
    CircularMeasureOptions o = simulated_circular_measure(emulator_config(d, program));
    o.stop = &stop;
    o.tolerance_um = 1000;  // the machine file's circularity_um: kept with the session through the resume
    const CircularMeasureResult first = measure_circular(store, p, op, o);
    ASSERT_TRUE(first.summary.interrupted) << first.summary.reason;
    ASSERT_TRUE(first.session_id.has_value());
    const std::int64_t id = *first.session_id;
    EXPECT_EQ(store.session(id).state, storage::SessionState::interrupted);
    EXPECT_FALSE(first.stored.has_value()) << "nothing analysed before the test is complete";
    try {
        throw_unless_completed(first.summary, first.session_id, "the resume line");
        FAIL() << "an interrupted run is not a completed one";
    } catch (const Error& e) {
        EXPECT_EQ(e.category(), ErrorCategory::interrupted);
        EXPECT_NE(std::string(e.what()).find("the resume line"), std::string::npos) << e.what();
    }

    const PreparedCircular again = resume_circular_session(store, std::to_string(id));
    ASSERT_EQ(again.session, id);
    ASSERT_TRUE(again.before.has_value());
    EXPECT_EQ(again.before->state, storage::SessionState::interrupted);
    EXPECT_EQ(again.test.radius_mm, 100.0) << "the stored test";
    EXPECT_GE(again.first_attempt, 1);
    ProgramOperator op2(program, acq::circular_program(again.test, again.dialect, again.dwell_s));
    const CircularMeasureResult second =
        measure_circular(store, again, op2, simulated_circular_measure(d.path / "emulator.json"));
    ASSERT_EQ(second.summary.final_state, acq::State::Done) << second.summary.reason;
    EXPECT_EQ(second.session_id, id) << "the same session";
    EXPECT_EQ(store.session(id).state, storage::SessionState::completed);
    ASSERT_TRUE(second.stored.has_value());
    EXPECT_NEAR(diagnostic(second.stored->payload_json, "backlash_x_um"), 3.0, 0.6);
    const auto stored = nlohmann::json::parse(second.stored->payload_json);
    EXPECT_EQ(stored["tolerance"]["circularity_um"], 1000.0) << "the resumed session is judged as it was begun";
    EXPECT_TRUE(stored["tolerance"]["pass"].get<bool>());
}

TEST(CircularMeasureUseCase, OnlyACircularSessionThatExistsIsTakenUp) {
    ballbar::test::ScratchDir d{"circular-wf"};
    storage::Store store((d.path / "c.db").string());
    try {
        (void)resume_circular_session(store, "42");
        FAIL() << "no error";
    } catch (const std::exception& e) {
        EXPECT_EQ(category_of(e), ErrorCategory::not_found) << e.what();
    }
    storage::NewSession ns;
    ns.procedure = "ssm-two-step";
    const std::int64_t ssm = store.create_session(ns);
    store.start_session(ssm);
    store.transition(ssm, storage::SessionState::interrupted, "test");
    try {
        (void)resume_circular_session(store, std::to_string(ssm));
        FAIL() << "took up an SSM session";
    } catch (const Error& e) {
        EXPECT_EQ(e.category(), ErrorCategory::bad_input);
        EXPECT_NE(std::string(e.what()).find("not a circular test"), std::string::npos) << e.what();
    }
    EXPECT_EQ(store.session(ssm).state, storage::SessionState::interrupted) << "nothing changed";
}

TEST(CircularAnalysisUseCase, ASessionAnalysedAgainStoresNoDuplicateAndItsFileGivesTheSameResult) {
    ballbar::test::ScratchDir d{"circular-wf"};
    storage::Store store((d.path / "c.db").string());
    const fs::path program = d.path / "circle.nc";
    PreparedCircular p;
    p.test = xy_test();
    ProgramOperator op(program, acq::circular_program(p.test, p.dialect, p.dwell_s));
    const CircularMeasureResult r =
        measure_circular(store, p, op, simulated_circular_measure(emulator_config(d, program)));
    ASSERT_TRUE(r.session_id.has_value());
    const std::string key = std::to_string(*r.session_id);
    const auto circular_results = [&] {
        int n = 0;
        for (const auto& res : store.results(*r.session_id)) n += res.kind == "circular";
        return n;
    };
    const StoreOpener opener = [&store]() -> storage::Store& { return store; };
    const std::vector<std::string> inputs{key};
    for (int i = 0; i < 2; ++i) {
        const CircularAnalysis again = analyze_circular_inputs(inputs, opener, opener, {});
        ASSERT_EQ(again.tests.size(), 1u);
        EXPECT_FALSE(again.tests[0].stored) << "the session already holds this result";
        EXPECT_EQ(again.tests[0].payload_json, r.stored->payload_json);
    }
    EXPECT_EQ(circular_results(), 1);
    CircularAnalyzeOptions with_tolerance;
    with_tolerance.tolerance_um = 50.0;  // another verdict: another result, stored once
    EXPECT_TRUE(analyze_circular_inputs(inputs, opener, opener, with_tolerance).tests[0].stored);
    EXPECT_FALSE(analyze_circular_inputs(inputs, opener, opener, with_tolerance).tests[0].stored);
    EXPECT_EQ(circular_results(), 2);

    // The session's trace as a file, analysed as a file: the same figures, nothing stored.
    const fs::path trace = d.path / "exported.csv";
    std::ofstream(trace) << export_session(store, *r.session_id, ExportFormat::trace);
    const std::vector<std::string> files{trace.string()};
    const CircularAnalysis from_file = analyze_circular_inputs(files, opener, opener, {});
    ASSERT_EQ(from_file.tests.size(), 1u);
    EXPECT_FALSE(from_file.tests[0].input.session.has_value());
    EXPECT_NEAR(from_file.tests[0].result.runs[0].circularity_um, r.stored->result.runs[0].circularity_um, 1e-3);
    EXPECT_EQ(circular_results(), 2);

    // Tests that cannot be combined (one plane twice) and an input that is neither a file nor a session
    // are refused, storing nothing.
    for (const std::vector<std::string>& refused :
         {std::vector<std::string>{key, trace.string()}, std::vector<std::string>{"/no/such/trace.csv"}}) {
        try {
            analyze_circular_inputs(refused, opener, opener, with_tolerance);
            ADD_FAILURE() << "analysed " << refused.back();
        } catch (const Error& e) {
            EXPECT_EQ(e.category(), ErrorCategory::bad_input) << e.what();
        }
    }
    EXPECT_EQ(circular_results(), 2);

    // The 3 µm of X backlash the machine has, in LinuxCNC's terms (joint 0 is X).
    const ControllerSettings cs = controller_settings(r.stored->result, "linuxcnc");
    ASSERT_EQ(cs.axes.size(), 2u);
    EXPECT_EQ(cs.axes[0].axis, 'X');
    ASSERT_TRUE(cs.axes[0].backlash_mm.has_value());
    EXPECT_NEAR(*cs.axes[0].backlash_mm, 0.003, 0.0006);
    EXPECT_EQ(cs.axes[0].setting.rfind("[JOINT_0] BACKLASH = 0.00", 0), 0u) << cs.axes[0].setting;
    EXPECT_THROW(controller_settings(r.stored->result, "acme"), Error);
}

TEST(CircularPlanUseCase, ARateTooSlowForTheFeedAndATestBeyondTheTravelAreRefused) {
    const circ::TestSpec t = xy_test();
    // 1000 mm/min at 1000 readings/s: 0.017 mm between samples, plenty.
    EXPECT_NE(check_feed_for_rate(t, 1000.0).find("highest usable feed"), std::string::npos);
    try {
        check_feed_for_rate(t, 1.0);  // 16.7 mm between samples
        FAIL() << "a feed too fast for the rate was accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.category(), ErrorCategory::bad_input);
        EXPECT_NE(std::string(e.what()).find("too fast"), std::string::npos) << e.what();
    }
    const acq::MachineFile machine = acq::parse_machine_file(
        R"({"type": "TTTRR", "name": "small", "a_pivot_mm": [0, 0, 0], "c_offset_mm": [0, 0, -100],
            "travel": {"X_mm": [-50, 50], "Y_mm": [-400, 400], "Z_mm": [-400, 400]}})");
    try {
        circular_part_program(t, analysis::NcDialect::Fanuc, 1.0, &machine);
        FAIL() << "a test beyond X's travel was planned";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("travel of X"), std::string::npos) << e.what();
    }
    EXPECT_EQ(circular_part_program(t, analysis::NcDialect::Fanuc, 1.0),
              acq::circular_program(t, analysis::NcDialect::Fanuc, 1.0));
}

}  // namespace
}  // namespace ballbar::workflow
