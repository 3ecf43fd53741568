// SPDX-License-Identifier: MIT
// The emulator's configuration: every number finite and within its documented range
// (docs/emulator.md, "Configuration file"), refused naming the key; the project's own configurations
// stay valid.
#include <gtest/gtest.h>

#include <string>

#include "ballbar/device/emulator.hpp"

namespace ballbar::device {
namespace {

struct Case {
    const char* name;
    const char* json;
    const char* says;
};

void PrintTo(const Case& c, std::ostream* os) {
    *os << c.name;
}

class BadEmulatorConfig : public ::testing::TestWithParam<Case> {};

TEST_P(BadEmulatorConfig, IsRefusedNamingTheKey) {
    const Case& c = GetParam();
    try {
        parse_emulator_config(c.json);
        FAIL() << "accepted " << c.json;
    } catch (const std::invalid_argument& e) {
        EXPECT_EQ(std::string(e.what()).rfind("emulator config: ", 0), 0u) << e.what();
        EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << e.what();
    }
}

INSTANTIATE_TEST_SUITE_P(
    Keys, BadEmulatorConfig,
    ::testing::Values(
        Case{"noise_1e308", R"({"instrument": {"noise_um": 1e308}})", "instrument.noise_um = 1e+308 is outside"},
        Case{"zero_offset_1e308", R"({"instrument": {"zero_offset_um": -1e308}})", "instrument.zero_offset_um"},
        Case{"temp_start_1e308", R"({"instrument": {"temp_start_C": 1e308}})", "instrument.temp_start_C"},
        Case{"temp_drift_1e308", R"({"instrument": {"temp_drift_C_per_h": 1e308}})", "temp_drift_C_per_h"},
        Case{"ripple_period_zero", R"({"instrument": {"temp_ripple_period_s": 0}})", "temp_ripple_period_s = 0"},
        Case{"battery_200", R"({"instrument": {"battery_start_pct": 200}})", "battery_start_pct = 200"},
        Case{"watchdog_negative", R"({"instrument": {"watchdog_s": -1}})", "watchdog_s = -1"},
        Case{"socket_1e308", R"({"machine": {"socket_mm": [0, 1e308, 0]}})", "machine.socket_mm[1] = 1e+308"},
        Case{"tool_ball_1e308", R"({"machine": {"tool_ball_mm": [1e308, 0, 0]}})", "machine.tool_ball_mm[0]"},
        Case{"start_X_1e308", R"({"machine": {"start": {"X_mm": 1e308}}})", "machine.start.X_mm = 1e+308"},
        Case{"start_A_1e308", R"({"machine": {"start": {"A_deg": 1e308}}})", "machine.start.A_deg = 1e+308"},
        Case{"rapid_1e308", R"({"machine": {"rapid_mm_min": 1e308}})", "machine.rapid_mm_min = 1e+308"},
        Case{"rapid_zero", R"({"machine": {"rapid_deg_min": 0}})", "machine.rapid_deg_min = 0"},
        Case{"error_X0C_1e308", R"({"machine": {"errors": {"X0C": 1e308}}})", "machine.errors.X0C: X0C = 1e+308"},
        Case{"error_B0A_deg_200", R"({"machine": {"errors": {"B0A_deg": 200}}})", "machine.errors.B0A_deg: B0A ="},
        Case{"reply_delay_1e308", R"({"faults": {"reply_delay_ms": 1e308}})", "faults.reply_delay_ms = 1e+308"},
        Case{"stall_negative", R"({"faults": {"stall_s": -5}})", "faults.stall_s = -5"},
        Case{"disconnect_at_1e308", R"({"faults": {"disconnect_at_s": 1e308}})", "faults.disconnect_at_s"},
        Case{"start_delay_1e308", R"({"faults": {"start_delay_s": 1e308}})", "faults.start_delay_s"},
        Case{"drop_probability_2", R"({"faults": {"drop_frame_probability": 2}})", "faults.drop_frame_probability"},
        Case{"unknown_key", R"({"seeed": 1})", "emulator config: unknown key \"seeed\" (known: seed, time"},
        Case{"unknown_machine_key", R"({"machine": {"sockt_mm": [0, 0, 0]}})", "machine: unknown key \"sockt_mm\""},
        Case{"unknown_axis_key", R"({"continuous": {"backlash_um": {"W": 1}}})",
             "continuous.backlash_um: unknown key \"W\" (known: X, Y, Z)"}),
    [](const auto& param_info) { return std::string(param_info.param.name); });

TEST(EmulatorConfig, TheProjectsOwnConfigurationsStayValid) {
    for (const char* f : {"tttrr-emulator.json", "tttrr-emulator-measure.json"})
        EXPECT_NO_THROW(load_emulator_config(std::string(BALLBAR_TEST_DATA_DIR) + "/machines/" + f)) << f;
    EXPECT_NO_THROW(parse_emulator_config(R"({"faults": {"stall_at_s": -1, "disconnect_at_s": -1}})"));
}

}  // namespace
}  // namespace ballbar::device
