// SPDX-License-Identifier: MIT
// The circular test's demo as a use case (`ballbar demo --test circular`, and any front end): an emulated
// machine with every effect of docs/formats/trace.md at a few µm, its ball-bar on a pty through the real
// protocol, the guided circular procedure into a new session, and the diagnosis checked against the
// emulator's truth by the accuracy rule of docs/circular.md.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "ballbar/acquisition/circular_session.hpp"
#include "ballbar/acquisition/interfaces.hpp"
#include "ballbar/analysis/circular.hpp"
#include "ballbar/device/continuous_machine.hpp"
#include "ballbar/device/emulator.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::workflow {

struct CircularDemoOptions {
    analysis::circular::TestSpec test;  ///< the bar's length is its radius
    std::uint64_t seed = 1;
    device::FaultConfig faults;  ///< the link's faults (docs/emulator.md, "faults")
    std::string notes;           ///< stored with the session (the command that made it)
    /// Called once the emulator serves and the session exists: the pty's path and the session id.
    std::function<void(const std::string& pty, std::int64_t session)> on_started;
    const std::atomic<bool>* stop = nullptr;  ///< set: the session stops, resumable, keeping what it measured
};

struct CircularDemoResult {
    std::int64_t session = 0;
    acquisition::CircularSummary summary;
    analysis::circular::CircularResult result;
    std::vector<device::TruthComparison> checks;            ///< each diagnostic against the emulator's truth
    bool pass = false;                                      ///< every check within the rule
    std::uint64_t dropped_frames = 0, replayed_frames = 0;  ///< the emulated link's faults, as it counted them
};

/// The demo machine's continuous errors: every effect of trace.md at once, each at a few µm radially.
device::ContinuousErrors circular_demo_errors();

/// Runs the demo into a new session of `store` with `op` answering the procedure's questions. Error (of
/// the category the run ended in) when it did not complete; a diagnosis that misses the truth is
/// returned with pass false.
CircularDemoResult run_circular_demo(storage::Store& store, const CircularDemoOptions& options,
                                     acquisition::Operator& op);

}  // namespace ballbar::workflow
