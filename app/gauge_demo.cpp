// SPDX-License-Identifier: MIT
// `ballbar demo --instrument KIND`: the SSM demo on an emulated digital gauge (workflow/gauge_demo.hpp),
// printed as measured against true errors.
#include "ballbar/workflow/gauge_demo.hpp"

#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "ballbar/device/gauge.hpp"
#include "command.hpp"
#include "gauge_commands.hpp"
#include "json_out.hpp"

namespace ballbar::app {

int run_gauge_demo(const GaugeDemoOptions& o, const std::string& db_path) {
    namespace gg = ballbar::device::gauge;
    namespace ba = ballbar::analysis;
    using demo_json = nlohmann::ordered_json;
    const auto kind = gg::parse_kind(o.instrument);
    if (!kind) throw Error(ErrorCategory::bad_input, "--instrument must be sylvac, mitutoyo-itn, digimatic or modbus");
    const auto type = ba::parse_machine_type(o.machine);
    if (!type) throw Error(ErrorCategory::bad_input, "--machine must be RRTTT, TTTRR or RTTTR");
    workflow::GaugeDemoOptions demo;
    demo.kind = *kind;
    demo.machine = *type;
    demo.seed = o.seed;
    demo.rate_hz = o.rate_hz;
    demo.notes =
        "ballbar demo --instrument " + o.instrument + " --machine " + o.machine + " --seed " + std::to_string(o.seed);
    storage::StoreOptions so;
    so.sync_full = false;
    storage::Store store(db_path, so);
    demo.on_started = [&](const std::string& uri, std::int64_t, const acquisition::Plan& plan) {
        if (!o.json)
            std::cout << "ballbar demo: " << o.machine << " (" << plan.machine.geometry.name << "), "
                      << plan.points.size() << " points, on an emulated " << o.instrument << " gauge at " << o.rate_hz
                      << " readings/s (" << uri << ")\n";
    };
    const workflow::GaugeDemoResult r = workflow::run_gauge_demo(store, demo);

    demo_json out;
    out["session"] = r.session;
    out["machine"] = o.machine;
    out["instrument"] = demo_json::parse(r.instrument_json);
    out["locations"] = demo_json::array();
    for (const auto& l : r.locations)
        out["locations"].push_back({{"test", l.test},
                                    {"step", l.step},
                                    {"e_mm", vec3_json(l.measured_mm)},
                                    {"true_e_mm", vec3_json(l.true_mm)}});
    out["orientation"] = demo_json::array();
    for (const auto& t : r.orientation) {
        demo_json oj = {{"test", t.test}, {"kind", std::string(acquisition::to_string(t.kind))}};
        put_angles(oj, "", "", t.measured, *type, t.kind);
        put_angles(oj, "true_", "", t.truth, *type, t.kind);
        out["orientation"].push_back(std::move(oj));
    }
    out["max_location_error_um"] = r.max_location_error_um;
    out["max_orientation_error_arcsec"] = r.max_orientation_error_arcsec;
    out["samples"] = r.summary.samples;
    if (o.json) {
        std::cout << out.dump() << std::endl;
        return kExitOk;
    }
    std::printf("\nTotal position errors (SSM exact), µm: measured | true\n");
    for (const auto& l : r.locations)
        std::printf("  test %d step %d   %8.3f %8.3f %8.3f | %8.3f %8.3f %8.3f\n", l.test, l.step,
                    1e3 * l.measured_mm.x(), 1e3 * l.measured_mm.y(), 1e3 * l.measured_mm.z(), 1e3 * l.true_mm.x(),
                    1e3 * l.true_mm.y(), 1e3 * l.true_mm.z());
    std::printf("\nLargest difference from the truth: %.3f µm (positions), %.3f\" (orientations).\n",
                r.max_location_error_um, r.max_orientation_error_arcsec);
    const auto& ij = out["instrument"];
    std::printf("Gauge: %s %s, %.1f readings/s, resolution %.4g µm.\n", ij["maker"].get<std::string>().c_str(),
                ij["model"].get<std::string>().c_str(), ij["reading_rate_hz"].get<double>(),
                1e3 * ij["resolution_mm"].get<double>());
    std::printf("Session %lld stored in %s (%zu samples).\n", static_cast<long long>(r.session), store.path().c_str(),
                r.summary.samples);
    return kExitOk;
}

}  // namespace ballbar::app
