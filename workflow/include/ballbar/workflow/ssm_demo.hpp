// SPDX-License-Identifier: MIT
// The guided two-step SSM procedure on the emulator, as one use case (`ballbar demo`, and the web page's
// demo button to come): a seed-like machine with known errors and a 0.1 µm bar, served on a
// pseudo-terminal by a thread of this process on simulated time; the procedure talks to it through the
// real path (serial transport → protocol → driver), stores the session, and the result holds what it
// measured next to the emulator's truth, with every stored point checked against where the emulated
// machine truly stood (docs/procedure.md).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/acquisition/compute.hpp"
#include "ballbar/acquisition/interfaces.hpp"
#include "ballbar/acquisition/plan.hpp"
#include "ballbar/acquisition/session.hpp"
#include "ballbar/device/emulator.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::workflow {

/// Answers every question like the plan and drives the emulated machine as its operator would: runs each
/// program it is told to start (late, at a feed override, when the faults say so), presses cycle start at
/// every program stop and moves the socket when the stop says so. Progress and messages go to the
/// callbacks a front end gives.
class EmulatedOperator : public acquisition::ScriptedOperator {
  public:
    EmulatedOperator(const acquisition::Plan& plan, device::SimulatedMachine& machine,
                     const device::FaultConfig& faults)
        : acquisition::ScriptedOperator(plan.spec.answers),
          machine_(machine),
          start_delay_s_(faults.start_delay_s),
          feed_override_(faults.feed_override),
          answer_delay_s_(faults.answer_delay_s) {}
    void run_program(const analysis::NcProgram& program, std::span<const std::size_t>, bool) override;
    void program_stop(const acquisition::ProgramStop& stop) override;
    void progress(const acquisition::Progress& p) override {
        if (on_progress) on_progress(p);
    }
    void message(std::string_view text) override {
        if (on_message) on_message(text);
    }

    std::function<void(const acquisition::Progress&)> on_progress;
    std::function<void(std::string_view)> on_message;
    int programs = 0;

  private:
    device::SimulatedMachine& machine_;
    double start_delay_s_, feed_override_, answer_delay_s_;
};

/// What the emulator's truth says of a stored session: each stored point's window of samples against
/// where the emulated machine truly stood at each sample's time (pose and socket), and the stored stream
/// for samples stored twice (the same device time).
struct TruthCheck {
    std::size_t points = 0;
    std::size_t wrong_pose = 0;    ///< points with a window sample away from the point's planned pose
    std::size_t stored_twice = 0;  ///< stored samples whose device time another stored sample has
    std::size_t samples_stored = 0;
    std::string first_wrong;  ///< the first wrong point, for the message
};
/// Needs the machine's history (SimulatedMachine::keep_history before the session). A sample is at its
/// point's pose when within `linear_mm` and `angle_rad` of it (a machine that compensates stands a
/// correction away from the planned pose; the neighbouring dwells of a point are 0.45 mm away or more).
TruthCheck check_against_truth(storage::Store& store, std::int64_t session_id, const device::Emulator& emulator,
                               double linear_mm = 1e-4, double angle_rad = 1e-6);

struct SsmDemoOptions {
    analysis::MachineType machine = analysis::MachineType::TTTRR;
    std::uint64_t seed = 1;                     ///< the emulator's noise: same seed, same session
    std::optional<acquisition::PlanSpec> plan;  ///< default: acquisition::default_plan of the seed machine
    device::FaultConfig faults;                 ///< the emulator's faults (docs/emulator.md)
    std::string notes;                          ///< stored with the session
    acquisition::Tolerances tolerances;         ///< the demo machine's, for the verdict (none: no verdict)
    /// A registered machine (`demo --asset`): the emulated machine has its geometry (the type's demo
    /// errors) and the session is stored under its asset id; its tolerances judge unless `tolerances` has any.
    std::optional<acquisition::MachineFile> registered;
    std::string machine_asset;
    /// The front end's operator (a web page): it answers the questions and is told of each program and
    /// program stop before the emulated machine runs it — the machine waits for the operator as a real
    /// one would. Empty: the plan's answers, at once (the CLI's demo).
    acquisition::Operator* front = nullptr;
    const std::atomic<bool>* stop = nullptr;  ///< set: the session stops, resumable, keeping its points
};

/// What a front end hears while the demo runs.
struct SsmDemoEvents {
    /// Once the emulator serves and the session is stored: its id, the plan, the emulator's pty.
    std::function<void(std::int64_t session_id, const acquisition::Plan& plan, const std::string& pty)> started;
    std::function<void(const acquisition::Progress&)> progress;
    std::function<void(std::string_view)> message;  ///< what the procedure waits for, and how long
};

/// One location measured, and its truth.
struct LocationVsTruth {
    acquisition::LocationResult measured;  ///< as stored (read back through its codec)
    analysis::Vec3 true_mm = analysis::Vec3::Zero();
};

struct SsmDemoResult {
    std::int64_t session_id = 0;
    acquisition::MachineFile machine;
    acquisition::Plan plan;
    acquisition::SessionSummary summary;
    std::vector<LocationVsTruth> locations;
    std::vector<acquisition::TrueTest> truth;  ///< per test, in plan order (summary.tests[i].test indexes it)
    TruthCheck check;
    std::uint64_t dropped_frames = 0, replayed_frames = 0, corrupted_bytes = 0;  ///< the faults the link suffered
};

/// Runs the demo into `store`. Throws Error (failed) when the session did not end done — the points it did
/// store are checked against the truth all the same and the message says how they fared — or when a
/// stored point is away from its pose or a sample stored twice; Error (device) when the emulator cannot
/// serve.
SsmDemoResult run_ssm_demo(storage::Store& store, const SsmDemoOptions& options, const SsmDemoEvents& events = {});

}  // namespace ballbar::workflow
