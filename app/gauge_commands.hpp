// SPDX-License-Identifier: MIT
// The CLI's gauge commands: `demo --instrument`, `monitor` and `emulate --instrument` on a gauge
// (gauge_demo.cpp, gauge_commands.cpp). The gauge as a sample source is workflow/gauge_source.hpp.
#pragma once

#include <cstdint>
#include <string>

namespace ballbar::app {

/// `ballbar demo --instrument KIND`: the SSM procedure on the emulated gauge sitting on the simulated
/// machine; prints measured vs true errors like the plain demo. `db_path` as resolve_db_path gives it.
struct GaugeDemoOptions {
    std::string instrument;
    std::string machine = "TTTRR";
    std::uint64_t seed = 1;
    double rate_hz = 20;
    bool json = false;
};
int run_gauge_demo(const GaugeDemoOptions& o, const std::string& db_path);

/// `ballbar monitor --device GAUGE-URI`: live readings of a gauge, a summary at the end.
int run_gauge_monitor(const std::string& uri, double seconds, bool json, double rate_hz);

/// `ballbar emulate --instrument KIND --pty`: a serial gauge emulator on a pty until Ctrl-C.
int run_gauge_emulate(const std::string& kind, const std::string& faults, std::uint64_t seed, double rate_hz);

}  // namespace ballbar::app
