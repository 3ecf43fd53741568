// SPDX-License-Identifier: MIT
// `ballbar emulate --pty | --tcp PORT [--config FILE] [--seed N]`: the emulated instrument as a
// standalone process, behind a pseudo-terminal (connect with serial:/dev/pts/N) or a loopback TCP port
// (tcp:127.0.0.1:PORT). Prints where it listens on stdout (one line; a new line after each simulated
// reconnect) and serves until SIGINT/SIGTERM.
#include <csignal>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "ballbar/device/emulator.hpp"
#include "ballbar/device/emulator_host.hpp"
#include "ballbar/workflow/gauge_source.hpp"
#include "command.hpp"
#include "gauge_commands.hpp"
#include "interrupt.hpp"

namespace {

struct EmulateOptions {
    bool pty = false;
    int tcp_port = -1;
    std::string config;
    std::optional<std::uint64_t> seed;
    bool fast = false;
    std::string link;
    std::optional<double> watchdog_s;
    bool verbose = false;
    std::string instrument;  ///< a gauge kind (gauge_commands.cpp)
    std::string faults;
    double rate_hz = 20;
};

int run_emulate(const EmulateOptions& o) {
    using namespace ballbar;
    using ballbar::app::Error;
    using ballbar::app::ErrorCategory;
    if (o.pty == (o.tcp_port >= 0)) throw Error(ErrorCategory::bad_input, "give exactly one of --pty and --tcp PORT");
    if (!o.link.empty()) {
        if (!o.pty) throw Error(ErrorCategory::bad_input, "--link is for --pty: it links to the pseudo-terminal");
        std::error_code ec;
        const auto st = std::filesystem::symlink_status(o.link, ec);
        if (!ec && std::filesystem::exists(st))
            throw Error(ErrorCategory::bad_input, "--link " + o.link +
                                                      ": something is already there; ballbar emulate makes a new link "
                                                      "only and never replaces a file or link it did not make (remove "
                                                      "it, or choose another path)");
    }
    if (!o.instrument.empty() && o.instrument != "ballbar") {
        if (!o.pty) throw Error(ErrorCategory::bad_input, "--instrument " + o.instrument + " is served on --pty only");
        if (!o.link.empty())
            throw Error(ErrorCategory::bad_input, "--link is for the ball-bar emulator, not a gauge's");
        return app::run_gauge_emulate(o.instrument, o.faults, o.seed.value_or(1), o.rate_hz);
    }
    device::EmulatorConfig cfg;
    if (!o.config.empty()) {
        try {
            cfg = device::load_emulator_config(o.config);
        } catch (const std::invalid_argument& e) {
            throw Error(ErrorCategory::bad_input, e.what());
        }
    }
    if (o.seed) cfg.seed = *o.seed;
    // A standalone instrument stops streaming when its host vanishes (protocol.md, keep-alive).
    if (o.watchdog_s) {
        cfg.instrument.watchdog_s = *o.watchdog_s;
    } else if (cfg.instrument.watchdog_s == 0) {
        cfg.instrument.watchdog_s = 5;
    }
    device::Emulator emu(cfg);

    const app::InterruptGuard interrupt;  // Ctrl-C or SIGTERM: stop serving and exit
    std::signal(SIGPIPE, SIG_IGN);

    device::HostOptions opt;
    opt.pacing = o.fast ? device::Pacing::Simulated : device::Pacing::RealTime;
    opt.stop = app::InterruptGuard::flag();
    if (o.verbose) opt.on_event = [](const std::string& what) { std::cerr << "ballbar emulate: " << what << '\n'; };
    device::EmulatorHost host(emu, opt);
    std::cerr << "ballbar emulate: " << cfg.instrument.model << " serial " << cfg.instrument.serial << ", "
              << analysis::to_string(cfg.machine.geometry.type) << " machine, seed " << cfg.seed
              << (o.fast ? ", as fast as the host reads" : ", real time") << "; Ctrl-C to stop\n";
    if (o.pty) {
        host.run_pty(
            [](const std::string& path) {
                std::cout << path << std::endl;  // flushed: the caller waits for this line
            },
            o.link);
    } else {
        if (o.tcp_port > 65535) throw Error(ErrorCategory::bad_input, "--tcp PORT must be 0..65535");
        device::TcpListener listener(static_cast<std::uint16_t>(o.tcp_port));
        std::cout << "tcp:127.0.0.1:" << listener.port() << std::endl;
        host.run_tcp(listener);
    }
    return app::kExitOk;
}

}  // namespace

BALLBAR_COMMAND(emulate) {
    auto* sub = root.add_subcommand("emulate", "Run the emulated instrument behind a pseudo-terminal or a TCP port");
    auto o = std::make_shared<EmulateOptions>();
    sub->add_flag("--pty", o->pty, "Serve on a new pseudo-terminal; prints its path (use serial:PATH)");
    sub->add_option("--tcp", o->tcp_port, "Serve on 127.0.0.1:PORT (0 picks a free port); prints tcp:127.0.0.1:PORT")
        ->check(ballbar::app::in_range(0, 65535));
    sub->add_option("--config", o->config, "Emulator configuration (JSON, docs/emulator.md)");
    sub->add_option("--seed", o->seed, "Random seed (overrides the configuration's)");
    sub->add_flag("--fast", o->fast, "Stream as fast as the host reads instead of in real time");
    sub->add_option("--link", o->link, "Keep a symlink at this path to the current pty");
    sub->add_option("--watchdog", o->watchdog_s,
                    "Stop streaming after this many seconds without the host (default 5, 0 = never)")
        ->check(ballbar::app::in_range(0, 3600, "s"));
    sub->add_flag("-v,--verbose", o->verbose, "Log connections to stderr");
    sub->add_option("--instrument", o->instrument,
                    "ballbar (default), or a serial gauge: sylvac, digimatic, modbus (docs/instruments.md)")
        ->check(CLI::IsMember({"ballbar", "sylvac", "digimatic", "modbus", "mitutoyo-itn"}));
    sub->add_option("--faults", o->faults,
                    "Gauge faults: not-ready=P,out-of-range=P,no-reply=P,cut-off=P,inch,low-battery");
    sub->add_option("--rate", o->rate_hz, "Gauge readings per second")
        ->check(ballbar::app::in_range(1, 1000, "readings/s"));
    sub->callback([&globals, o] { globals.action = [o]() -> int { return run_emulate(*o); }; });
}
