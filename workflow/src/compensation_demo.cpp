// SPDX-License-Identifier: MIT
#include "ballbar/workflow/compensation_demo.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "ballbar/analysis/compensate.hpp"
#include "ballbar/analysis/identify.hpp"
#include "ballbar/analysis/kinematics.hpp"
#include "ballbar/analysis/nc_program.hpp"
#include "ballbar/analysis/plan_identification.hpp"
#include "ballbar/device/sim_machine.hpp"
#include "ballbar/storage/compensation_codec.hpp"

namespace ballbar::workflow {
namespace {

using namespace ballbar::analysis;

constexpr double kBarLengthMm = 100.0;
constexpr double kDwellS = 2.0;

MachineGeometry demo_geometry() {
    MachineGeometry g;
    g.type = MachineType::TTTRR;
    g.name = "emulated X'Y'ZA'C'";
    g.a_pivot_mm = Vec3(0, 0, 0);
    g.c_offset_mm = Vec3(0, 0, -100);
    return g;
}

// Seed-like errors: the rotary block's location errors dominate (tens of µm, tens of µrad); the
// linear axes add a few µm/m of scale and squareness. EZZ cannot be identified from cube-corner SSM
// (every bar has the same Z component) and stays in the machine as an unmodelled error.
ErrorParams demo_truth() {
    ErrorParams e;
    e[Param::Y0A] = 0.025;
    e[Param::Z0A] = -0.018;
    e[Param::B0A] = 40e-6;
    e[Param::C0A] = -30e-6;
    e[Param::X0C] = 0.035;
    e[Param::Y0C] = -0.022;
    e[Param::A0C] = 50e-6;
    e[Param::B0C] = -35e-6;
    e[Param::EXX] = 8e-6;
    e[Param::EYY] = -6e-6;
    e[Param::EZZ] = 5e-6;
    e[Param::C0Y] = 10e-6;
    e[Param::B0Z] = -8e-6;
    e[Param::A0Z] = 6e-6;
    return e;
}

std::vector<Param> demo_params() {
    std::vector<Param> p = rotary_params_for(MachineType::TTTRR);
    for (Param q : {Param::EXX, Param::EYY, Param::EZZ, Param::C0Y, Param::B0Z, Param::A0Z}) p.push_back(q);
    return p;
}

// Measures every planned reading on the emulated machine: one SimulatedMachine per socket position
// (the socket is set up once, with its own offset), a rapid to the pose, a dwell, a bar reading.
ReadingSet measure_plan(const MachineGeometry& g, const ErrorParams& truth, const IdentificationPlan& plan,
                        double noise_mm, std::mt19937_64& rng) {
    ReadingSet rs = plan_readings(g, plan);
    std::uniform_real_distribution<double> offset(-0.03, 0.03);
    std::normal_distribution<double> noise(0.0, noise_mm);
    std::vector<Vec3> sockets;
    std::vector<std::unique_ptr<device::SimulatedMachine>> machines;  // not movable: it holds a mutex
    for (auto& r : rs.readings) {
        std::size_t k = 0;
        while (k < sockets.size() && (sockets[k] - r.socket_mm).norm() > 1e-9) ++k;
        if (k == sockets.size()) {
            device::MachineSetup setup;
            setup.geometry = g;
            setup.errors = truth;
            setup.socket_mm = r.socket_mm;
            setup.socket_offset_mm = Vec3(offset(rng), offset(rng), offset(rng));
            setup.start = r.pose;
            sockets.push_back(r.socket_mm);
            machines.push_back(std::make_unique<device::SimulatedMachine>(setup));
        }
        device::SimulatedMachine& m = *machines[k];
        m.rapid_to(r.pose);
        m.dwell(kDwellS);
        const double t = m.motion_end_s();
        r.time_s = t;
        r.measured_mm = m.bar_reading_mm(t, 20.0) + noise(rng);
    }
    return rs;
}

// Test path: the tool ball runs a wavy circle of radius 60 mm on the workpiece while A swings
// between 10° and 50° and C turns a full revolution (Lei & Hsu's path F has the same character).
std::vector<Pose> test_path(const MachineGeometry& g, int n) {
    std::vector<Pose> out;
    for (int k = 0; k < n; ++k) {
        const double s = 2.0 * kPi * k / n;
        Pose rot;
        rot.A_rad = deg_to_rad(30.0 + 20.0 * std::sin(2.0 * s));
        rot.C_rad = s - kPi;
        const Vec3 w(60.0 * std::cos(s), 60.0 * std::sin(s), 20.0 + 10.0 * std::sin(3.0 * s));
        out.push_back(command_for_tool_ball(g, rot, nominal_table_ball(g, rot, w)));
    }
    return out;
}

struct AxisRms {
    Vec3 rms = Vec3::Zero();
    double max_mm = 0;
};

// Tool-ball error relative to the table (actual − intended, table frame) along a path run.
AxisRms path_error(const MachineModel& actual, const MachineModel& nominal, const std::vector<Pose>& intended,
                   const std::vector<Pose>& run) {
    AxisRms out;
    for (std::size_t i = 0; i < run.size(); ++i) {
        const Vec3 d = actual.tool_pose(run[i]).position_mm - nominal.tool_pose(intended[i]).position_mm;
        out.rms += d.cwiseAbs2();
        out.max_mm = std::max(out.max_mm, d.norm());
    }
    out.rms = (out.rms / static_cast<double>(run.size())).cwiseSqrt();
    return out;
}

// Runs poses as an NC program on the emulated machine: written in the Fanuc dialect (what a
// controller would receive, with its 0.1 µm / 0.0001° resolution), parsed back, executed, and the
// commanded pose sampled at the end of every block.
std::vector<Pose> run_on_emulator(const MachineGeometry& g, const ErrorParams& truth, const std::vector<Pose>& poses) {
    NcProgram prog;
    prog.dialect = NcDialect::Fanuc;
    for (const Pose& p : poses) {
        NcBlock b;
        b.motion = NcMotion::Feed;
        b.X_mm = p.X_mm;
        b.Y_mm = p.Y_mm;
        b.Z_mm = p.Z_mm;
        b.A_rad = p.A_rad;
        b.C_rad = p.C_rad;
        b.feed_mm_min = 2000;
        prog.blocks.push_back(b);
    }
    const NcProgram parsed = parse_nc_program(write_nc_program(prog, "compensated test path"), NcDialect::Fanuc);
    device::MachineSetup setup;
    setup.geometry = g;
    setup.errors = truth;
    setup.start = poses.front();
    device::SimulatedMachine m(setup);
    std::vector<Pose> out;
    for (const NcBlock& b : parsed.blocks) {
        if (b.motion != NcMotion::Feed) continue;
        Pose p = out.empty() ? poses.front() : out.back();
        if (b.X_mm) p.X_mm = *b.X_mm;
        if (b.Y_mm) p.Y_mm = *b.Y_mm;
        if (b.Z_mm) p.Z_mm = *b.Z_mm;
        if (b.A_rad) p.A_rad = *b.A_rad;
        if (b.C_rad) p.C_rad = *b.C_rad;
        m.move_to(p, *b.feed_mm_min);
        out.push_back(m.pose_at(m.motion_end_s()));
    }
    return out;
}

}  // namespace

double CompensationDemo::improvement(int axis) const {
    return rms_after_um[axis] > 0 ? rms_before_um[axis] / rms_after_um[axis] : 0.0;
}

CompensationDemo run_compensation_demo(const CompensationDemoOptions& opt) {
    const MachineGeometry g = demo_geometry();
    const ErrorParams truth = demo_truth();
    std::mt19937_64 rng(opt.seed);
    CompensationDemo demo;

    // 1. Plan: the locations that make the model observable.
    PlanOptions po;
    po.params = demo_params();
    po.bar_length_mm = kBarLengthMm;
    po.target_independence = 0.3;
    po.min_readings_per_unknown = 4.0;
    const IdentificationPlan plan = plan_identification(g, po);
    std::vector<Param> free;
    for (const auto& p : plan.params)
        if (p.observable) free.push_back(p.param);
    demo.locations = plan.locations.size();
    demo.not_identifiable = plan.unreachable;

    // 2. Measure the plan on the emulated machine, 3. identify.
    const ReadingSet readings = measure_plan(g, truth, plan, opt.noise_um * 1e-3, rng);
    demo.readings = readings.readings.size();
    FitOptions fo;
    fo.free_params = free;
    demo.fit = fit_error_model(readings, fo);
    // What the plan can identify of the truth: the same plan, sockets and fit on noise-free readings.
    // EZZ is held at zero (every cube-corner bar has the same Z component, so a scale common to the
    // three axes is a bar-length change): the fit measures EXX − EZZ, EYY − EZZ, and the locations the
    // common scale moves. An estimate is judged against this, its truth for this plan, not the machine's.
    std::mt19937_64 rng_noise_free(opt.seed);
    const FitSummary target = fit_error_model(measure_plan(g, truth, plan, 0.0, rng_noise_free), fo);
    for (const auto& e : demo.fit.estimates) {
        if (!e.param) continue;
        IdentifiedParam p{e, truth[*e.param], 0.0};
        for (const auto& t : target.estimates)
            if (t.param == e.param) p.identifiable_value = t.estimate;
        demo.identified.push_back(p);
    }

    // 4. Compensate the test path with the identified model, 5. run both programs on the emulator.
    const std::vector<Pose> path = test_path(g, std::max(opt.path_points, 8));
    const Compensator comp(g, demo.fit.model);
    std::vector<Pose> compensated;
    for (const Pose& u : path) {
        const Correction c = opt.first_order ? comp.first_order(u) : comp.exact(u);
        demo.singular_blocks += c.singular;
        compensated.push_back(c.commanded);
    }
    const MachineModel actual(g, truth), nominal(g, ErrorParams{});
    const AxisRms before = path_error(actual, nominal, path, run_on_emulator(g, truth, path));
    const AxisRms after = path_error(actual, nominal, path, run_on_emulator(g, truth, compensated));
    for (int a = 0; a < 3; ++a) {
        demo.rms_before_um[a] = before.rms[a] * 1e3;
        demo.rms_after_um[a] = after.rms[a] * 1e3;
    }
    demo.max_after_um = after.max_mm * 1e3;
    demo.path_blocks = static_cast<int>(path.size());
    demo.exact = !opt.first_order;
    return demo;
}

void store_compensation_demo(storage::Store& store, std::int64_t session, const CompensationDemo& demo,
                             std::uint64_t seed) {
    storage::CompensationRecord stored;
    stored.metric = "RMS tool-ball error over a " + std::to_string(demo.path_blocks) +
                    "-block test path, before and after " + (demo.exact ? "exact" : "first-order") +
                    " compensation (compensation demo: its own emulated TTTRR machine, seed " + std::to_string(seed) +
                    ")";
    for (int a = 0; a < 3; ++a)
        stored.axes.push_back({std::string(1, "XYZ"[a]), demo.rms_before_um[a], demo.rms_after_um[a]});
    store.add_result(session, std::string(storage::kCompensationResultKind), storage::compensation_to_json(stored),
                     std::nullopt, "ballbar demo/1");
}

}  // namespace ballbar::workflow
