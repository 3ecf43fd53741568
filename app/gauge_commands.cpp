// SPDX-License-Identifier: MIT
// The gauge paths of `ballbar monitor` and `ballbar emulate`, and `ballbar udev-rules` (the gauge udev
// rules from the ID table).
#include "gauge_commands.hpp"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "ballbar/device/gauge_emulator.hpp"
#include "ballbar/device/ids.hpp"
#include "ballbar/workflow/gauge_source.hpp"
#include "command.hpp"
#include "interrupt.hpp"
#include "json_out.hpp"

namespace ballbar::app {

namespace gg = ballbar::device::gauge;

int run_gauge_monitor(const std::string& uri, double seconds, bool json, double rate_hz) {
    using namespace std::chrono;
    const InterruptGuard interrupt;
    std::signal(SIGPIPE, SIG_IGN);
    std::unique_ptr<gg::GaugeSampler> sampler;
    gg::Identity id;
    try {
        gg::BarOnGauge bar;
        bar.calibrated_length_mm = 0;  // the gauge's own reading
        bar.target_rate_hz = rate_hz;
        sampler = std::make_unique<gg::GaugeSampler>(gg::open_gauge(uri), bar);
        id = sampler->identify();
    } catch (const std::invalid_argument& e) {
        throw Error(ErrorCategory::bad_input, e.what());
    } catch (const device::DeviceError& e) {
        throw Error(ErrorCategory::failed, e.what());
    }
    if (!json)
        std::cout << id.maker << " " << id.model << (id.serial.empty() ? "" : " serial " + id.serial)
                  << (id.firmware.empty() ? "" : " (" + id.firmware + ")") << ", unit " << (id.inch ? "inch" : "mm")
                  << (id.low_battery ? ", LOW BATTERY" : "") << "  (" << sampler->gauge().uri() << ")\n";
    std::uint64_t n = 0;
    double mean = 0, m2 = 0;
    std::string failure;
    const bool tty = ::isatty(STDOUT_FILENO);
    const auto start = steady_clock::now();
    auto next_show = start;
    try {
        while (!InterruptGuard::requested()) {
            if (seconds > 0 && steady_clock::now() - start >= duration<double>(seconds)) break;
            const auto s = sampler->poll(milliseconds(500));
            if (!s) continue;
            const double mm = s->displacement_nm * 1e-6;
            ++n;
            const double d = mm - mean;
            mean += d / static_cast<double>(n);
            m2 += d * (mm - mean);
            if (!json && steady_clock::now() >= next_show) {
                const auto& st = sampler->stats();
                char line[200];
                std::snprintf(line, sizeof line, "%+11.5f mm  %6.1f readings/s  resolution %.4g µm  gaps %llu", mm,
                              st.rate_hz, st.resolution_mm * 1e3,
                              static_cast<unsigned long long>(st.not_ready + st.out_of_range + st.timeouts +
                                                              st.invalid + st.errors));
                std::cout << (tty ? "\r" : "") << line << (tty ? "" : "\n") << std::flush;
                next_show = steady_clock::now() + milliseconds(500);
            }
        }
    } catch (const device::DeviceError& e) {
        failure = e.what();
    }
    if (!json && tty) std::cout << '\n';
    const auto& st = sampler->stats();
    const double std_mm = n > 1 ? std::sqrt(m2 / static_cast<double>(n - 1)) : 0.0;
    if (json) {
        // As the ball-bar's monitor: no readings give null, not 0; sd is the readings' spread.
        const auto or_null = [n](double v) {
            return n > 0 ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
        };
        nlohmann::ordered_json j{{"device", uri},
                                 {"kind", gg::to_string(id.kind)},
                                 {"maker", text_or_null(id.maker)},
                                 {"model", text_or_null(id.model)},
                                 {"serial", text_or_null(id.serial)},
                                 {"firmware", text_or_null(id.firmware)},
                                 {"inch", id.inch},
                                 {"low_battery", id.low_battery},
                                 {"samples", n},
                                 {"mean_mm", or_null(mean)},
                                 {"sd_mm", n > 1 ? nlohmann::ordered_json(std_mm) : nlohmann::ordered_json(nullptr)},
                                 {"rate_hz", st.rate_hz},
                                 {"resolution_mm", st.resolution_mm},
                                 {"not_ready", st.not_ready},
                                 {"out_of_range", st.out_of_range},
                                 {"timeouts", st.timeouts},
                                 {"invalid", st.invalid},
                                 {"errors", st.errors},
                                 {"error", text_or_null(failure)}};
        std::cout << j.dump() << '\n';
    } else {
        std::cout << n << " readings, " << st.rate_hz << " readings/s, mean " << mean << " mm, std " << std_mm * 1e3
                  << " µm; not ready " << st.not_ready << ", out of range " << st.out_of_range << ", no reply "
                  << st.timeouts << ", invalid " << st.invalid << "\n";
    }
    if (!failure.empty()) throw Error(ErrorCategory::failed, failure);
    return InterruptGuard::requested() ? kExitInterrupted : kExitOk;
}

namespace {

gg::GaugeFaults parse_gauge_faults(const std::string& spec) {
    gg::GaugeFaults f;
    std::stringstream ss(spec);
    std::string item;
    while (std::getline(ss, item, ',')) {
        if (item.empty()) continue;
        const auto eq = item.find('=');
        const std::string key = item.substr(0, eq);
        double p = 0;
        if (eq != std::string::npos) {
            try {
                std::size_t used = 0;
                p = std::stod(item.substr(eq + 1), &used);
                if (used != item.size() - eq - 1 || !(p >= 0 && p <= 1)) throw std::invalid_argument("range");
            } catch (const std::exception&) {
                throw Error(ErrorCategory::bad_input, "--faults: '" + item + "': a probability must be 0..1");
            }
        }
        if (key == "inch" && eq == std::string::npos) {
            f.inch = true;
        } else if (key == "low-battery" && eq == std::string::npos) {
            f.low_battery = true;
        } else if (key == "not-ready" && eq != std::string::npos) {
            f.not_ready_probability = p;
        } else if (key == "out-of-range" && eq != std::string::npos) {
            f.out_of_range_probability = p;
        } else if (key == "no-reply" && eq != std::string::npos) {
            f.no_reply_probability = p;
        } else if (key == "cut-off" && eq != std::string::npos) {
            f.cut_off_probability = p;
        } else {
            throw Error(ErrorCategory::bad_input,
                        "--faults: unknown item '" + item +
                            "' (not-ready=P, out-of-range=P, no-reply=P, cut-off=P, inch, low-battery)");
        }
    }
    return f;
}

}  // namespace

int run_gauge_emulate(const std::string& kind_name, const std::string& faults, std::uint64_t seed, double rate_hz) {
    const auto kind = gg::parse_kind(kind_name);
    if (!kind)
        throw Error(ErrorCategory::bad_input, "--instrument must be sylvac, digimatic or modbus (serial gauges)");
    if (*kind == gg::Kind::MitutoyoItn)
        throw Error(ErrorCategory::bad_input,
                    "--instrument mitutoyo-itn is a USB device: it has no pty emulator (use `ballbar demo "
                    "--instrument mitutoyo-itn`)");
    gg::GaugeEmulatorConfig cfg;
    cfg.kind = *kind;
    cfg.seed = seed;
    cfg.rate_hz = rate_hz;
    cfg.faults = parse_gauge_faults(faults);
    if (*kind == gg::Kind::Sylvac) cfg.resolution_mm = 0.001;
    gg::GaugeEmulator emu(cfg, {}, false);
    const InterruptGuard interrupt;
    std::signal(SIGPIPE, SIG_IGN);
    gg::GaugePtyHost host(emu);
    std::cerr << "ballbar emulate: " << kind_name << " gauge, " << rate_hz << " readings/s, seed " << seed
              << "; Ctrl-C to stop\n";
    std::cout << host.path() << std::endl;  // flushed: the caller waits for this line
    while (!InterruptGuard::requested()) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    return kExitOk;
}

}  // namespace ballbar::app

BALLBAR_COMMAND(udev_rules) {
    auto* sub = root.add_subcommand("udev-rules", "Print the gauges' udev rules from the gauge ID table");
    auto plugdev = std::make_shared<bool>(false);
    sub->add_flag("--plugdev", *plugdev, "The plugdev-group variant (udev/plugdev/)");
    sub->callback([&globals, plugdev] {
        globals.action = [plugdev]() -> int {
            std::cout << ballbar::device::gauge_udev_rules(*plugdev);
            return ballbar::app::kExitOk;
        };
    });
}
