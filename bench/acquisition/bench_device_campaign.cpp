// SPDX-License-Identifier: MIT
// The fault campaign through the real device path: each session is one `ballbar demo --json` process
// (the emulator on a pty, on simulated time; the serial transport, the frame codec, the driver, the
// guided procedure, SQLite), with a plan file and a faults object this program writes at random: the
// three machine types, the three layouts, 1–4 tests at one or two socket positions; a disconnect of
// 0.2–10 s at a random time (in two sessions of three), 1–5 % of stream frames dropped, corrupted
// bytes on the link (rejected by the codec's CRC), 0–2 % of frames replayed, the machine started 0–60 s
// late, a feed override of 50–150 %, and the operator pressing cycle start 0–120 s after each stop.
//
// The demo checks every stored point against the emulator's truth (the pose and socket where the
// machine stood at each sample of the point's window) and the stored stream for repeats, and exits
// non-zero when a point is at a wrong pose; this program adds up its figures.
//   bench_device_campaign BALLBAR_EXE [SESSIONS=200] [FIRST_SEED=1] [JOBS=4]
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;

struct Figures {
    int sessions = 0, done = 0, interrupted = 0, failed = 0, refused_plans = 0;
    std::vector<std::string> reasons;  ///< of the interrupted sessions
    std::size_t points = 0, wrong_pose = 0, stored_twice = 0, disconnects = 0;
    std::size_t samples_stored = 0, dropped_frames = 0, replayed_frames = 0, corrupted_bytes = 0;
    std::size_t programs = 0, void_dwells = 0;
    double worst_position_um = 0, worst_angle_arcsec = 0;
    std::vector<std::string> problems;
};

/// One session's plan file (ballbar-plan/1) and faults object, from its seed.
struct Case {
    std::string type, plan, faults;
    bool disconnect = false;
};

Case make_case(std::uint64_t seed, bool simple) {
    std::mt19937_64 rng(seed);
    auto uni = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
    Case c;
    const char* types[] = {"RRTTT", "TTTRR", "RTTTR"};
    const char* layouts[] = {"cube-corner", "four-point", "six-point"};
    c.type = types[seed % 3];
    json tests = json::array();
    // The default plan's tests of each type (docs/procedure.md).
    if (c.type == "RRTTT") {
        for (auto [a, b] : {std::pair{30, 0}, {0, 40}, {45, 60}, {30, 60}})
            tests.push_back({{"socket_mm", {-50, -15, 150}}, {"rotation_deg", {{"A", a}, {"B", b}}}});
    } else if (c.type == "TTTRR") {
        for (auto [a, g] : {std::pair{0, 30}, {15, 0}, {10, 30}, {10, 45}})
            tests.push_back({{"socket_mm", {-49.275, -14.312, -77.777}}, {"rotation_deg", {{"A", a}, {"C", g}}}});
    } else {
        for (auto [k, v] : {std::pair{"B", 30}, {"B", -20}, {"A", 15}, {"A", -10}})
            tests.push_back({{"socket_mm", {-30, 20, 60}}, {"rotation_deg", {{k, v}}}});
    }
    const std::size_t n_tests = 1 + (seed / 9) % 4;
    tests.erase(tests.begin() + static_cast<std::ptrdiff_t>(n_tests), tests.end());
    if (!simple && (seed / 2) % 2 == 1 && n_tests > 1)  // a second socket position for the later tests
        for (std::size_t t = n_tests / 2; t < n_tests; ++t) {
            auto& s = tests[t]["socket_mm"];
            s = {s[0].get<double>() + 20, s[1].get<double>() - 10, s[2].get<double>()};
        }
    json plan = {{"format", "ballbar-plan/1"},
                 {"bar_length_mm", 100},
                 {"layout", simple ? "cube-corner" : layouts[(seed / 3) % 3]},
                 {"tests", tests}};
    c.plan = plan.dump();
    const double span_s = 6.0 * static_cast<double>(n_tests) * 2 * 6 + 60;
    json f = {{"drop_frame_probability", uni(0.01, 0.05)},
              {"corrupt_byte_probability", uni(0, 0.0005)},
              {"replay_frame_probability", uni(0, 0.02)},
              {"start_delay_s", uni(0, 60)},
              {"feed_override", uni(0.5, 1.5)},
              {"answer_delay_s", uni(0, 120)}};
    if (rng() % 3 != 0) {
        c.disconnect = true;
        f["disconnect_at_s"] = uni(5, span_s);
        f["disconnect_s"] = uni(0.2, 10);
    }
    c.faults = f.dump();
    return c;
}

/// Runs `cmd`; its exit code, and stdout in `out`.
int run(const std::string& cmd, std::string& out) {
    FILE* p = ::popen(cmd.c_str(), "r");
    if (!p) return -1;
    std::array<char, 4096> buf{};
    std::size_t n;
    while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) out.append(buf.data(), n);
    const int st = ::pclose(p);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

void run_session(const std::string& exe, const fs::path& dir, std::uint64_t seed, Figures& f, std::mutex& m) {
    const fs::path db = dir / ("s" + std::to_string(seed) + ".db");
    const fs::path plan = dir / ("s" + std::to_string(seed) + ".plan.json");
    const fs::path err = dir / ("s" + std::to_string(seed) + ".err");
    Case c = make_case(seed, false);
    // The session's database (with its journal and lock), and with `all` its plan and stderr too.
    auto remove_files = [&](bool all) {
        for (const char* suffix : {"", "-wal", "-shm", ".lock"}) fs::remove(db.string() + suffix);
        if (all) {
            fs::remove(plan);
            fs::remove(err);
        }
    };
    std::string out;
    int code = 0;
    bool refused = false;
    for (int attempt = 0; attempt < 2; ++attempt) {
        std::ofstream(plan) << c.plan;
        out.clear();
        code = run(exe + " --db " + db.string() + " demo --json --seed " + std::to_string(seed) + " --machine " +
                       c.type + " --plan " + plan.string() + " --faults '" + c.faults + "' 2>" + err.string(),
                   out);
        if (code != 2 || attempt == 1) break;
        refused = true;  // a plan shape this machine's travel refuses: the simple shape, same faults
        const std::string faults = c.faults;
        c = make_case(seed, true);
        c.faults = faults;
        remove_files(false);
    }
    std::lock_guard lock(m);
    ++f.sessions;
    f.refused_plans += refused;
    f.disconnects += c.disconnect;
    auto problem = [&](const std::string& what) {
        std::ifstream e(err);
        std::stringstream es;
        es << e.rdbuf();
        f.problems.push_back("seed " + std::to_string(seed) + " (" + c.type + ", faults " + c.faults + "): " + what +
                             ": " + es.str());
    };
    if (code != 0) {
        // Ended interrupted (the instrument gone for good, or points missing after every retry) is a
        // finished session when it is resumable; anything else is not.
        std::string shown;
        json st;
        if (run(exe + " --db " + db.string() + " sessions show 1 --json 2>/dev/null", shown) == 0) try {
                st = json::parse(shown).at("session");
            } catch (const json::exception&) {
            }
        if (code == 1 && st.is_object() && st.value("state", "") == "interrupted" && st.value("resumable", false)) {
            ++f.interrupted;
            f.reasons.push_back("seed " + std::to_string(seed) + ": " + st.value("state_reason", ""));
            f.points += st.value("point_count", 0u);
            remove_files(true);
            return;
        }
        ++f.failed;
        problem("exit " + std::to_string(code));
        return;
    }
    json j;
    try {
        j = json::parse(out);
    } catch (const json::exception& e) {
        ++f.failed;
        problem(std::string("unreadable JSON: ") + e.what());
        return;
    }
    ++f.done;
    const auto& t = j.at("truth_check");
    f.points += t.at("points").get<std::size_t>();
    f.wrong_pose += t.at("wrong_pose").get<std::size_t>();
    f.stored_twice += t.at("stored_twice").get<std::size_t>();
    f.samples_stored += t.at("samples_stored").get<std::size_t>();
    f.dropped_frames += t.at("dropped_frames").get<std::size_t>();
    f.replayed_frames += t.at("replayed_frames").get<std::size_t>();
    f.corrupted_bytes += t.at("corrupted_bytes").get<std::size_t>();
    f.programs += j.at("programs").get<std::size_t>();
    f.void_dwells += j.at("void_dwells").get<std::size_t>();
    for (const auto& l : j.at("locations")) {
        double d2 = 0;
        for (int k = 0; k < 3; ++k)
            d2 += std::pow(l.at("measured_mm")[k].get<double>() - l.at("true_mm")[k].get<double>(), 2);
        f.worst_position_um = std::max(f.worst_position_um, 1e3 * std::sqrt(d2));
    }
    for (const auto& o : j.at("orientation"))
        if (o.at("true_rad").is_object() && o.at("measured_rad").is_object())
            for (const auto& [k, v] : o.at("true_rad").items())
                f.worst_angle_arcsec = std::max(
                    f.worst_angle_arcsec, std::abs(o.at("measured_rad").at(k).get<double>() - v.get<double>()) * 180.0 /
                                              3.141592653589793 * 3600.0);
    if (t.at("wrong_pose").get<std::size_t>() > 0) problem("points at a wrong pose");
    remove_files(true);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: bench_device_campaign BALLBAR_EXE [SESSIONS=200] [FIRST_SEED=1] [JOBS=4]\n");
        return 2;
    }
    const std::string exe = argv[1];
    const int sessions = argc > 2 ? std::atoi(argv[2]) : 200;
    const std::uint64_t first = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 1;
    const int jobs = std::max(1, argc > 4 ? std::atoi(argv[4]) : 4);
    // A directory of this program's own (never one the user named): it removes only what it wrote.
    std::string tmpl = (fs::temp_directory_path() / "ballbar-device-campaign-XXXXXX").string();
    if (!::mkdtemp(tmpl.data())) {
        std::perror("mkdtemp");
        return 1;
    }
    const fs::path dir = tmpl;
    Figures f;
    std::mutex m;
    std::atomic<int> next{0};
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<std::thread> pool;
    for (int w = 0; w < jobs; ++w)
        pool.emplace_back([&] {
            for (int i; (i = next++) < sessions;) run_session(exe, dir, first + static_cast<std::uint64_t>(i), f, m);
        });
    for (auto& t : pool) t.join();
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::error_code ec;
    fs::remove(dir, ec);  // empty unless a session failed (its files are kept for a look)

    std::printf(
        "sessions                           %d: completed %d, interrupted and resumable %d, not finished %d "
        "(%d plans refused by the travel, run with the simple shape)\n",
        f.sessions, f.done, f.interrupted, f.failed, f.refused_plans);
    std::printf("points stored                      %zu\n", f.points);
    std::printf("points stored at a wrong pose      %zu\n", f.wrong_pose);
    std::printf("samples stored twice               %zu\n", f.stored_twice);
    std::printf("disconnects injected               %zu\n", f.disconnects);
    std::printf("frames dropped / replayed          %zu / %zu; bytes corrupted %zu\n", f.dropped_frames,
                f.replayed_frames, f.corrupted_bytes);
    std::printf("samples stored                     %zu\n", f.samples_stored);
    std::printf("programs run (first + retries)     %zu\n", f.programs);
    std::printf("void dwells (never stored)         %zu\n", f.void_dwells);
    std::printf("worst |e - true| of the sessions   %.3f um, %.3f arcsec\n", f.worst_position_um, f.worst_angle_arcsec);
    std::printf("wall time                          %.1f s (%d at a time)\n", secs, jobs);
    for (const auto& r : f.reasons) std::printf("interrupted: %s\n", r.c_str());
    for (const auto& p : f.problems) std::printf("problem: %s\n", p.c_str());
    if (!f.problems.empty()) std::printf("kept for a look: %s\n", dir.c_str());
    return f.wrong_pose == 0 && f.failed == 0 && f.stored_twice == 0 ? 0 : 1;
}
