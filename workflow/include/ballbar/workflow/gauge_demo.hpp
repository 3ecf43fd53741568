// SPDX-License-Identifier: MIT
// The SSM demo on a digital gauge as a use case (`ballbar demo --instrument KIND`, and any front end):
// the guided two-step SSM procedure on a bar built on an emulated gauge that sits on the simulated
// machine (its displacement follows the machine's bar length) and runs on a simulated clock that each
// reading advances by 1/rate, so a 20 readings/s gauge is as slow as it is on a real bar. The serial
// gauges are reached through a pty and the real drivers (libserialport/termios, libmodbus), the USB-ITN
// through its driver over an in-process USB link. Measured errors are set against the true ones.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ballbar/acquisition/plan.hpp"
#include "ballbar/acquisition/session.hpp"
#include "ballbar/analysis/types.hpp"
#include "ballbar/device/gauge.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::workflow {

struct GaugeDemoOptions {
    device::gauge::Kind kind = device::gauge::Kind::Sylvac;
    analysis::MachineType machine = analysis::MachineType::TTTRR;
    std::uint64_t seed = 1;
    double rate_hz = 20;
    std::string notes;  ///< stored with the session (the command that made it)
    /// Called once the session exists and the gauge is reachable: its URI, the session, the plan.
    std::function<void(const std::string& uri, std::int64_t session, const acquisition::Plan& plan)> on_started;
};

/// One SSM location: the total position error measured (SSM exact) and the machine's true one.
struct GaugeDemoLocation {
    int test = 0;  ///< from 1
    int step = 0;
    analysis::Vec3 measured_mm = analysis::Vec3::Zero();
    analysis::Vec3 true_mm = analysis::Vec3::Zero();
};

/// One test's orientation errors (exact model), measured and true.
struct GaugeDemoOrientation {
    int test = 0;  ///< from 1
    acquisition::TestKind kind{};
    analysis::OrientationErrors measured, truth;
};

struct GaugeDemoResult {
    std::int64_t session = 0;
    std::string machine_name;
    std::string instrument_json;  ///< the gauge as stored: maker, model, resolution_mm, reading_rate_hz, …
    acquisition::SessionSummary summary;
    std::vector<GaugeDemoLocation> locations;
    std::vector<GaugeDemoOrientation> orientation;
    double max_location_error_um = 0;         ///< largest |measured − true| of a coordinate
    double max_orientation_error_arcsec = 0;  ///< of the angles each test observes
};

/// Runs the demo into a new session of `store`. Error (failed) when the procedure did not complete
/// (the session keeps the state it ended in).
GaugeDemoResult run_gauge_demo(storage::Store& store, const GaugeDemoOptions& options);

}  // namespace ballbar::workflow
