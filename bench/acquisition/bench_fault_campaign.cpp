// SPDX-License-Identifier: MIT
// The fault campaign (tests/acquisition/fault_campaign.hpp): ≥ 200 randomised emulated sessions on
// simulated time, and the figures docs/procedure.md quotes.
//   bench_fault_campaign [SESSIONS [FIRST_SEED]]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fault_campaign.hpp"

int main(int argc, char** argv) {
    const int sessions = argc > 1 ? std::atoi(argv[1]) : 210;
    const std::uint64_t seed = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 1;
    if (argc > 3 && std::string(argv[3]) == "log") {  // one session's transitions
        ballbar::acquisition::testing::CampaignFigures one;
        std::vector<ballbar::acquisition::TransitionRecord> log;
        ballbar::acquisition::testing::run_campaign_session(seed, one, &log);
        for (const auto& t : log)
            std::printf("%s -> %s %s: %s\n", std::string(to_string(t.from)).c_str(),
                        std::string(to_string(t.to)).c_str(), std::string(to_string(t.event)).c_str(),
                        t.detail.c_str());
        return 0;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const auto f = ballbar::acquisition::testing::run_campaign(sessions, seed);
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("sessions                          %d (done %d, interrupted with an exact retry list %d)\n", f.sessions,
                f.done, f.interrupted_with_exact_retry);
    std::printf("points stored                     %zu\n", f.points_stored);
    std::printf("points stored at a wrong pose     %zu\n", f.wrong_pose);
    std::printf("sessions not finished             %d\n", f.not_finished);
    std::printf("disconnects injected              %zu\n", f.faults);
    std::printf("samples lost per fault (max)      %zu (%.1f ms at 1 kHz)\n", f.max_lost_per_fault,
                static_cast<double>(f.max_lost_per_fault));
    std::printf("samples stored twice              %zu\n", f.stored_twice);
    std::printf("frames' samples dropped / replayed %zu / %zu\n", f.dropped_samples, f.replayed_samples);
    std::printf("void dwells (never stored)        %zu\n", f.void_dwells);
    std::printf("programs run (first + retries)    %zu\n", f.programs);
    std::printf("worst |e - true| of done sessions %.3f um, %.3f arcsec\n", f.max_position_error_um,
                f.max_angle_error_arcsec);
    std::printf("wall time                         %.1f s\n", secs);
    if (argc > 3) std::printf("%s", f.interrupted_reasons.c_str());
    if (!f.first_problem.empty()) std::printf("first problem: %s\n", f.first_problem.c_str());
    return f.wrong_pose == 0 && f.not_finished == 0 && f.stored_twice == 0 ? 0 : 1;
}
