// SPDX-License-Identifier: MIT
// The fault campaign: randomised sessions of the guided procedure against the simulated machine, over
// the three machine types and every plan shape (layout, number of tests, one or more socket positions),
// with disconnects of 0.2–10 s at random times (during moves, codes and dwells), 1–5 % of frames lost
// (dropped, or rejected for a corrupted byte), replayed frames, the machine started 0–60 s late, a feed
// override of 50–150 % and operator answers after 0–120 s. The source knows the machine's true pose at
// every sample, so every stored point is checked against the pose the plan says. Used by
// bench/acquisition/bench_fault_campaign (≥ 200 sessions) and, reduced, by a ctest test.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <random>
#include <set>
#include <string>

#include "ballbar/acquisition/compute.hpp"
#include "ballbar/acquisition/session.hpp"
#include "sim_source.hpp"

namespace ballbar::acquisition::testing {

struct CampaignFigures {
    int sessions = 0;
    int done = 0;
    int interrupted_with_exact_retry = 0;  ///< ended resumable, `missing` = exactly the points not stored
    int not_finished = 0;                  ///< anything else (must be 0)
    std::size_t points_stored = 0;
    std::size_t wrong_pose = 0;          ///< stored points whose window was not at the planned pose (must be 0)
    std::size_t stored_twice = 0;        ///< samples stored twice (must be 0)
    std::size_t faults = 0;              ///< disconnects injected
    std::size_t max_lost_per_fault = 0;  ///< samples delivered by the source but not stored, per fault
    std::size_t void_dwells = 0, programs = 0, dropped_samples = 0, replayed_samples = 0;
    double max_position_error_um = 0;  ///< done sessions: |measured − true| of SSM's e, worst location
    double max_angle_error_arcsec = 0;
    std::string first_problem;
    std::string interrupted_reasons;
};

/// A fixed link instead of the campaign's random one: these probabilities, no disconnects.
struct CampaignLink {
    double drop_frame_probability = 0, replay_frame_probability = 0;
};

inline void run_campaign_session(std::uint64_t seed, CampaignFigures& f, std::vector<TransitionRecord>* log = nullptr,
                                 const CampaignLink* link = nullptr) {
    std::mt19937_64 rng(seed);
    auto uni = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
    const analysis::MachineType types[] = {analysis::MachineType::RRTTT, analysis::MachineType::TTTRR,
                                           analysis::MachineType::RTTTR};
    const analysis::LayoutKind layouts[] = {analysis::LayoutKind::CubeCorner, analysis::LayoutKind::FourPoint,
                                            analysis::LayoutKind::SixPoint};
    const auto type = types[seed % 3];
    const MachineFile m = seed_machine(type);
    PlanSpec spec = default_plan(m);
    spec.layout = layouts[(seed / 3) % 3];
    spec.tests.resize(1 + (seed / 9) % spec.tests.size());
    const bool sockets = (seed / 2) % 2 == 1 && spec.tests.size() > 1;
    if (sockets)  // a second socket position for the later tests
        for (std::size_t t = spec.tests.size() / 2; t < spec.tests.size(); ++t)
            spec.tests[t].socket_mm += analysis::Vec3(20, -10, 0);
    Plan plan;
    try {
        plan = make_plan(m, spec);
    } catch (const PlanError&) {
        spec.layout = analysis::LayoutKind::CubeCorner;  // a shape this machine's travel refuses
        plan = make_plan(m, spec);
    }
    SimOptions so;
    so.seed = seed * 7919 + 1;
    const double drop = uni(0.01, 0.05);
    so.drop_frame_probability = drop;
    so.replay_frame_probability = uni(0.0, 0.02);
    // Session length: about 5 s a point; disconnects anywhere in it.
    const double span = 5.0 * static_cast<double>(plan.points.size()) + 60;
    const int n_disc = static_cast<int>(rng() % 3);
    for (int i = 0; i < n_disc; ++i) so.disconnects.emplace_back(uni(5, span), uni(0.2, 10));
    std::sort(so.disconnects.begin(), so.disconnects.end());
    if (link) {
        so.drop_frame_probability = link->drop_frame_probability;
        so.replay_frame_probability = link->replay_frame_probability;
        so.disconnects.clear();
    }
    SimOperatorOptions oo;
    oo.late_start_s = uni(0, 60);
    oo.feed_override = uni(0.5, 1.5);
    auto delay_rng = std::make_shared<std::mt19937_64>(seed ^ 0x5eed);
    oo.answer_delay_s = [delay_rng] { return std::uniform_real_distribution<double>(0, 120)(*delay_rng); };
    device::MachineSetup setup;
    setup.geometry = plan.machine.geometry;
    setup.errors = demo_errors(type);
    setup.socket_mm = plan.points.front().socket_mm;
    setup.start = plan.points.front().pose;
    SimSource source(setup, plan, so);
    Answers answers;
    answers.on_point_failure = PointFailureAction::Retry;
    SimOperator op(&source, answers, oo);
    RecordingSink sink;
    std::size_t wrong = 0;
    sink.check_point = [&](const CapturedPoint& p) { wrong += !window_at_planned_pose(source, p); };
    Session session(plan, source, sink, op);
    const SessionSummary sum = session.run();
    if (log) *log = sink.transitions;

    ++f.sessions;
    f.points_stored += sink.points.size();
    f.wrong_pose += wrong;
    f.stored_twice += sink.repeated;
    f.faults += so.disconnects.size();
    f.void_dwells += sum.void_dwells;
    f.programs += sum.programs;
    f.dropped_samples += source.dropped_samples;
    f.replayed_samples += source.replayed_samples;
    // Every sample the source delivered (repeats aside) reached the sink.
    const std::size_t delivered = sum.samples;
    const std::size_t lost = delivered > sink.samples ? delivered - sink.samples : 0;
    f.max_lost_per_fault = std::max(f.max_lost_per_fault, so.disconnects.empty() ? lost : lost / so.disconnects.size());
    std::set<std::size_t> stored;
    for (const auto& p : sink.points) stored.insert(plan.index(p.planned.test, p.planned.step, p.planned.point));
    auto problem = [&](const std::string& what) {
        if (f.first_problem.empty()) f.first_problem = "seed " + std::to_string(seed) + ": " + what;
    };
    if (wrong) problem(std::to_string(wrong) + " points at a wrong pose");
    if (sum.final_state == State::Done) {
        ++f.done;
        if (stored.size() != plan.points.size()) problem("done without every point");
        const auto truth = true_values(plan, setup.errors);
        for (std::size_t t = 0; t < truth.size() && 2 * t + 1 < sink.locations.size(); ++t) {
            const auto& l1 = sink.locations[sink.locations.size() - 2 * truth.size() + 2 * t];
            const auto& l2 = sink.locations[sink.locations.size() - 2 * truth.size() + 2 * t + 1];
            f.max_position_error_um =
                std::max({f.max_position_error_um, 1e3 * (l1.ssm.exact_mm - truth[t].e1_mm).norm(),
                          1e3 * (l2.ssm.exact_mm - truth[t].e2_mm).norm()});
            const auto& got = sink.tests[sink.tests.size() - truth.size() + t].orientation;
            const auto& want = truth[t].result.orientation;
            if (got.exact && want.exact)
                f.max_angle_error_arcsec =
                    std::max({f.max_angle_error_arcsec,
                              analysis::rad_to_arcsec(std::abs(got.exact->d_alpha_rad - want.exact->d_alpha_rad)),
                              analysis::rad_to_arcsec(std::abs(got.exact->d_beta_rad - want.exact->d_beta_rad)),
                              analysis::rad_to_arcsec(std::abs(got.exact->d_gamma_rad - want.exact->d_gamma_rad))});
        }
    } else if (sum.interrupted) {
        std::set<std::size_t> expect_missing;
        for (std::size_t i = 0; i < plan.points.size(); ++i)
            if (!stored.count(i)) expect_missing.insert(i);
        if (std::set<std::size_t>(sum.missing.begin(), sum.missing.end()) == expect_missing &&
            !expect_missing.empty()) {
            ++f.interrupted_with_exact_retry;
            f.interrupted_reasons += "seed " + std::to_string(seed) + ": " + sum.reason + "\n";
        } else {
            ++f.not_finished;
            problem("interrupted without an exact list of its missing points");
        }
    } else {
        ++f.not_finished;
        problem(std::string("ended ") + std::string(to_string(sum.final_state)) + ": " + sum.reason);
    }
}

inline CampaignFigures run_campaign(int sessions, std::uint64_t first_seed = 1, const CampaignLink* link = nullptr) {
    CampaignFigures f;
    for (int i = 0; i < sessions; ++i)
        run_campaign_session(first_seed + static_cast<std::uint64_t>(i), f, nullptr, link);
    return f;
}

}  // namespace ballbar::acquisition::testing
