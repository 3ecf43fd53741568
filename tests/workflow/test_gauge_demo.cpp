// SPDX-License-Identifier: MIT
// The SSM demo on a digital gauge as a use case, in process (workflow::run_gauge_demo): for a gauge on a
// pty (its real driver: Sylvac, Digimatic, Modbus) and the USB-ITN (its driver over the in-process USB link), the
// measured total position errors match the simulated machine's true ones within 1 µm and the orientation errors within
// 2″, and the gauge's measured reading rate and resolution are stored with the session. The CLI's test
// (tests/app/test_cli_gauges.cpp) checks what `demo --instrument` prints and `sessions show` shows.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "../scratch_dir.hpp"
#include "ballbar/workflow/gauge_demo.hpp"

namespace ballbar::workflow {
namespace {

namespace gg = ballbar::device::gauge;

class GaugeDemoUseCase : public ::testing::TestWithParam<gg::Kind> {};

TEST_P(GaugeDemoUseCase, RecoversTheInjectedErrors) {
    test::ScratchDir d{"gauge-demo-wf"};
    storage::Store store(d.file("test.db"));
    GaugeDemoOptions o;
    o.kind = GetParam();
    o.rate_hz = 10;
    std::string uri;
    o.on_started = [&uri](const std::string& u, std::int64_t, const acquisition::Plan&) { uri = u; };
    const GaugeDemoResult r = run_gauge_demo(store, o);
    EXPECT_EQ(uri.rfind(gg::to_string(GetParam()), 0), 0u) << uri;
    EXPECT_EQ(store.session(r.session).state, storage::SessionState::completed);
    ASSERT_GE(r.locations.size(), 2u);
    EXPECT_LT(r.max_location_error_um, 1.0);
    EXPECT_LT(r.max_orientation_error_arcsec, 2.0);
    EXPECT_FALSE(r.orientation.empty());
    const auto inst = nlohmann::json::parse(r.instrument_json);
    EXPECT_NEAR(inst.at("reading_rate_hz").get<double>(), 10, 0.5);  // measured, on the gauge's clock
    EXPECT_NEAR(inst.at("resolution_mm").get<double>(), 1e-4, 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Gauges, GaugeDemoUseCase,
                         ::testing::Values(gg::Kind::Sylvac, gg::Kind::Digimatic, gg::Kind::Modbus,
                                           gg::Kind::MitutoyoItn),
                         [](const auto& p) {
                             std::string name = gg::to_string(p.param);
                             for (char& c : name)
                                 if (c == '-') c = '_';
                             return name;
                         });

}  // namespace
}  // namespace ballbar::workflow
