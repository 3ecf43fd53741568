// SPDX-License-Identifier: MIT
// What `ballbar serve` costs (issue 27's targets; docs/webui.md quotes the figures):
//   - the live stream: a server process whose operator gets a bar reading at 1 kHz (as a streaming
//     instrument's procedure reports it), with N viewers (default 20) on its event stream; the server
//     process's CPU (utime + stime from /proc, over `--seconds`) as a share of one core, and the live
//     updates each viewer received per second (the stream's 50 Hz cap);
//   - the page's load on the server: the requests a page makes when it opens (the page, its script,
//     style and icon, the procedure's state, the session list), timed from a client, median of 50.
// The server runs in a child process, so the viewers' own CPU is not counted.
// Usage: bench_serve [--viewers N] [--seconds S] [--runs R]
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "ballbar/webui/server.hpp"
// After Eigen (through the header above): httplib.h brings <resolv.h>, whose `_res` macro breaks Eigen.
#include <httplib.h>

namespace {

using Clock = std::chrono::steady_clock;

double cpu_seconds(pid_t pid) {
    std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
    std::string stat((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::istringstream rest(stat.substr(stat.rfind(')') + 2));
    std::string field;
    unsigned long long utime = 0, stime = 0;
    for (int i = 3; i <= 15; ++i) {  // fields 14 and 15 are utime and stime
        rest >> field;
        if (i == 14) utime = std::stoull(field);
        if (i == 15) stime = std::stoull(field);
    }
    return static_cast<double>(utime + stime) / static_cast<double>(::sysconf(_SC_CLK_TCK));
}

[[noreturn]] void serve_child(int port_fd, const std::string& db) {
    ballbar::webui::ServeOptions o;
    o.port = 0;
    o.db_path = db;
    ballbar::webui::Server server(o);
    const int port = server.bind();
    if (::write(port_fd, &port, sizeof port) != sizeof port) std::_Exit(2);
    std::atomic<bool> stop{false};
    std::thread feeder([&] {  // the instrument's readings as a procedure reports them, at 1 kHz
        auto& op = server.procedure().web_operator();
        ballbar::acquisition::Progress p;
        p.expected_mm = 100;
        auto next = Clock::now();
        for (std::uint64_t i = 0; !stop; ++i) {
            p.live_mm = 100 + 0.01 * std::sin(static_cast<double>(i) * 0.01);
            op.progress(p);
            next += std::chrono::milliseconds(1);
            std::this_thread::sleep_until(next);
        }
    });
    std::thread stopper([&] {
        sigset_t s;
        sigemptyset(&s);
        sigaddset(&s, SIGTERM);
        int sig = 0;
        sigwait(&s, &sig);
        stop = true;
        server.stop();
    });
    server.run();
    feeder.join();
    stopper.join();
    std::_Exit(0);
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
    int viewers = 20, runs = 3;
    double seconds = 5;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!std::strcmp(argv[i], "--viewers")) viewers = std::atoi(argv[i + 1]);
        if (!std::strcmp(argv[i], "--seconds")) seconds = std::atof(argv[i + 1]);
        if (!std::strcmp(argv[i], "--runs")) runs = std::atoi(argv[i + 1]);
    }
    char dir[] = "/tmp/ballbar-bench-serve-XXXXXX";
    if (!::mkdtemp(dir)) return 2;
    const std::string db = std::string(dir) + "/sessions.db";

    sigset_t s;
    sigemptyset(&s);
    sigaddset(&s, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &s, nullptr);  // the child's stopper sigwait()s for it
    int fds[2];
    if (::pipe(fds) != 0) return 2;
    const pid_t child = ::fork();
    if (child == 0) serve_child(fds[1], db);
    int port = 0;
    if (::read(fds[0], &port, sizeof port) != sizeof port) return 2;

    std::vector<double> cpu_pct, rates;
    for (int run = 0; run < runs; ++run) {
        std::atomic<bool> done{false};
        std::vector<std::atomic<long>> lives(static_cast<std::size_t>(viewers));
        std::vector<std::unique_ptr<httplib::Client>> clients;
        std::vector<std::thread> threads;
        for (int v = 0; v < viewers; ++v) {
            clients.push_back(std::make_unique<httplib::Client>("127.0.0.1", port));
            clients.back()->set_read_timeout(60, 0);
            threads.emplace_back([&, v] {
                const std::string path = "/api/events?client=bench-" + std::to_string(v);
                clients[static_cast<std::size_t>(v)]->Get(path.c_str(), [&](const char* d, std::size_t n) {
                    const std::string_view chunk(d, n);
                    for (std::size_t at = chunk.find("event: live"); at != std::string_view::npos;
                         at = chunk.find("event: live", at + 1))
                        ++lives[static_cast<std::size_t>(v)];
                    return !done.load();
                });
            });
        }
        std::this_thread::sleep_for(std::chrono::seconds(1));  // every stream open and flowing
        long before = 0;
        for (auto& l : lives) before += l;
        const double c0 = cpu_seconds(child);
        const auto t0 = Clock::now();
        std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
        const double c1 = cpu_seconds(child);
        const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
        long after = 0;
        for (auto& l : lives) after += l;
        done = true;
        for (auto& c : clients) c->stop();
        for (auto& t : threads) t.join();
        cpu_pct.push_back(100.0 * (c1 - c0) / wall);
        rates.push_back(static_cast<double>(after - before) / wall / viewers);
        std::printf("run %d: %d viewers, server CPU %.2f %% of one core, %.1f live updates/s per viewer\n", run + 1,
                    viewers, cpu_pct.back(), rates.back());
    }

    // The page's requests when it opens.
    httplib::Client c("127.0.0.1", port);
    std::vector<double> load_ms;
    for (int i = 0; i < 50; ++i) {
        const auto t0 = Clock::now();
        bool ok = true;
        for (const char* path : {"/", "/app.js", "/style.css", "/favicon.svg", "/api/procedure", "/api/sessions"}) {
            auto r = c.Get(path);
            ok = ok && r && r->status == 200;
        }
        if (!ok) {
            std::fprintf(stderr, "a page request failed\n");
            return 1;
        }
        load_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    }
    ::kill(child, SIGTERM);
    int status = 0;
    ::waitpid(child, &status, 0);
    std::filesystem::remove_all(dir);
    std::printf(
        "median of %d runs: server CPU %.2f %% of one core with %d viewers at %.1f updates/s each "
        "(target <= 10 %% at 50 Hz to 20)\n",
        runs, median(cpu_pct), viewers, median(rates));
    std::printf("page's requests when it opens (6, keep-alive): median %.2f ms of 50 (target: page load <= 300 ms)\n",
                median(load_ms));
    return 0;
}
