// SPDX-License-Identifier: MIT
// `ballbar monitor --device URI [--seconds N] [--json]`: connect, identify, stream and show the live
// reading, sample rate, lost frames and bar temperature; with --json a summary at the end.
#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "ballbar/device/gauge.hpp"
#include "ballbar/device/instrument.hpp"
#include "ballbar/device/uri.hpp"
#include "ballbar/workflow/gauge_source.hpp"
#include "command.hpp"
#include "gauge_commands.hpp"
#include "interrupt.hpp"
#include "json_out.hpp"

namespace {

struct MonitorOptions {
    std::string device;
    double seconds = 0;  ///< 0: until Ctrl-C
    bool json = false;
    std::optional<int> rate_hz;
    std::optional<int> averaging;
};

struct Summary {
    std::uint64_t n = 0;
    double mean = 0, m2 = 0;  // Welford, of the length in mm
    std::uint64_t first_us = 0, last_us = 0;
    std::optional<double> temp_C;  ///< the last sample's bar temperature; empty: it had none
    void add(const ballbar::analysis::BarSample& s, double length_mm) {
        if (n == 0) first_us = s.device_time_us;
        last_us = s.device_time_us;
        temp_C =
            (s.flags & ballbar::analysis::kSampleTempInvalid) ? std::nullopt : std::optional<double>(s.temperature_C());
        ++n;
        const double d = length_mm - mean;
        mean += d / static_cast<double>(n);
        m2 += d * (length_mm - mean);
    }
    double std_mm() const { return n > 1 ? std::sqrt(m2 / static_cast<double>(n - 1)) : 0.0; }
    double rate_hz() const {
        return n > 1 && last_us > first_us ? static_cast<double>(n - 1) * 1e6 / static_cast<double>(last_us - first_us)
                                           : 0.0;
    }
};

int run_monitor(const MonitorOptions& o) {
    using namespace ballbar;
    using app::Error;
    using app::ErrorCategory;
    using namespace std::chrono;
    if (device::gauge::is_gauge_uri(o.device))  // a digital gauge (docs/instruments.md)
        return app::run_gauge_monitor(o.device, o.seconds, o.json, o.rate_hz.value_or(20));
    const app::InterruptGuard interrupt;  // Ctrl-C ends the monitoring with a summary and exit 3
    std::signal(SIGPIPE, SIG_IGN);

    std::unique_ptr<device::Instrument> inst;
    try {
        inst = std::make_unique<device::Instrument>(device::open_transport(o.device));
    } catch (const std::invalid_argument& e) {
        throw Error(ErrorCategory::bad_input, e.what());
    }
    Summary sum;
    device::InstrumentInfo info;
    bool disconnected = false;
    std::string failure;
    try {
        info = inst->identify();
        if (!o.json) {
            std::cout << info.model << " serial " << info.serial << ", firmware " << info.firmware << ", protocol "
                      << info.protocol_version << ", bar " << info.calibrated_length_mm << " mm, resolution "
                      << info.resolution_um << " µm, range ±" << info.range_mm << " mm  (" << inst->transport().uri()
                      << ")\n";
        }
        const auto st = inst->status();
        if (st.streaming) inst->stop_streaming();  // a previous host left it streaming
        if (o.rate_hz || o.averaging) {
            inst->configure(o.rate_hz.value_or(st.sample_rate_hz), o.averaging.value_or(st.averaging));
        }
        inst->start_streaming();
        std::vector<analysis::BarSample> buf(8192);
        const auto start = steady_clock::now();
        auto next_show = start + milliseconds(500);
        const bool tty = ::isatty(STDOUT_FILENO);
        while (!app::InterruptGuard::requested()) {
            const auto now = steady_clock::now();
            if (o.seconds > 0 && now - start >= duration<double>(o.seconds)) break;
            inst->poll(milliseconds(20));
            std::size_t n;
            while ((n = inst->read_samples(buf)) > 0) {
                for (std::size_t i = 0; i < n; ++i) sum.add(buf[i], buf[i].length_mm(info.calibrated_length_mm));
                if (!o.json && now >= next_show) {
                    const auto& last = buf[n - 1];
                    char line[200];
                    std::snprintf(line, sizeof line, "%10.5f mm  (%+9.2f µm)%s  %7.1f Hz  lost frames %llu  %s",
                                  last.length_mm(info.calibrated_length_mm), last.displacement_nm * 1e-3,
                                  (last.flags & analysis::kSampleOutOfRange) ? " OUT OF RANGE" : "", sum.rate_hz(),
                                  static_cast<unsigned long long>(inst->stats().lost_frames),
                                  (last.flags & analysis::kSampleTempInvalid)
                                      ? "no bar temperature"
                                      : fmt::format("bar {:.2f} °C", last.bar_temp_C).c_str());
                    std::cout << (tty ? "\r" : "") << line << (tty ? "" : "\n") << std::flush;
                    next_show = now + milliseconds(500);
                }
            }
        }
        inst->stop_streaming();
        // Samples that arrived before StopReply.
        std::size_t n;
        while ((n = inst->read_samples(buf)) > 0) {
            for (std::size_t i = 0; i < n; ++i) sum.add(buf[i], buf[i].length_mm(info.calibrated_length_mm));
        }
        if (!o.json && tty) std::cout << '\n';
    } catch (const device::DeviceError& e) {
        disconnected = e.kind() == device::DeviceErrorKind::Disconnected;
        failure = e.what();
        // Nothing answered the ball-bar protocol on a serial port: a gauge there is what the operator meant.
        if (e.kind() == device::DeviceErrorKind::Timeout && sum.n == 0)
            failure += device::gauge::serial_gauge_hint(o.device);
    }
    const auto& st = inst->stats();
    // An instrument that answers but never streams is no working instrument: not "0 samples, std 0 µm".
    if (failure.empty() && sum.n == 0)
        failure =
            "the instrument answered but sent no samples: it does not stream (check its mode and cable, or "
            "power-cycle it)";
    const auto or_null = [&sum](double v) {
        return sum.n > 0 ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
    };
    if (o.json) {
        nlohmann::ordered_json j{{"samples", sum.n},
                                 {"lost_frames", st.lost_frames},
                                 {"rate_hz", or_null(sum.rate_hz())},
                                 {"mean_mm", or_null(sum.mean)},
                                 {"sd_mm", or_null(sum.std_mm())},  // the readings' spread (docs/cli.md)
                                 {"bar_temp_C", sum.temp_C && sum.n > 0 ? nlohmann::ordered_json(*sum.temp_C)
                                                                        : nlohmann::ordered_json(nullptr)},
                                 {"invalid_frames", st.invalid_frames},
                                 {"queue_drops", st.queue_drops},
                                 {"replayed_frames", st.replayed_frames},
                                 {"unknown_version_frames", st.unknown_version_frames},
                                 {"model", ballbar::app::text_or_null(info.model)},
                                 {"serial", ballbar::app::text_or_null(info.serial)},
                                 {"device", o.device},
                                 {"error", ballbar::app::text_or_null(failure)}};
        std::cout << j.dump() << '\n';
    } else if (sum.n > 0) {
        std::cout << sum.n << " samples, " << st.lost_frames << " lost frames, " << sum.rate_hz() << " Hz, mean "
                  << sum.mean << " mm, std " << sum.std_mm() * 1e3 << " µm\n";
    }
    if (!failure.empty()) {
        throw Error(ErrorCategory::failed, disconnected ? "instrument disconnected: " + failure : failure);
    }
    return app::InterruptGuard::requested() ? app::kExitInterrupted : app::kExitOk;
}

}  // namespace

BALLBAR_COMMAND(monitor) {
    auto* sub = root.add_subcommand("monitor", "Connect to an instrument and show its live reading");
    auto o = std::make_shared<MonitorOptions>();
    sub->add_option(
           "--device", o->device,
           "emulator:[CONFIG], serial:PATH, tcp:HOST:PORT, usb:VID:PID[:SERIAL], hid:VID:PID[:SERIAL]; gauges: "
           "sylvac:PATH, mitutoyo-itn:[SERIAL], digimatic:PATH, modbus:PATH[?slave=N&baud=B]")
        ->required();
    sub->add_option("--seconds", o->seconds, "Stream this long, then print the summary (default: until Ctrl-C)")
        ->check(ballbar::app::in_range(0, 604800, "s"));
    sub->add_flag("--json", o->json, "Print only a JSON summary at the end");
    sub->add_option("--rate", o->rate_hz, "Sample rate to configure, Hz")->check(ballbar::app::in_range(1, 5000, "Hz"));
    sub->add_option("--averaging", o->averaging, "Readings averaged per sample")->check(ballbar::app::in_range(1, 64));
    sub->callback([&globals, o] { globals.action = [o]() -> int { return run_monitor(*o); }; });
}
