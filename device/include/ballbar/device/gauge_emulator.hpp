// SPDX-License-Identifier: MIT
// The device side of the four gauge protocols (docs/instruments.md): a gauge on a bar whose displacement
// comes from a function of time (a still bar by default, the simulated machine in `ballbar demo
// --instrument`), answering in the exact grammar of its protocol, with faults (not ready, out of range,
// inch units, low battery, no reply, a reply cut off). Serial protocols are a DeviceEndpoint (behind a
// pty, `ballbar emulate --instrument KIND --pty`); the USB-ITN side answers control transfers and fills
// its interrupt-IN endpoint. Thread-safe: one link thread talks to it while others read its clock.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "ballbar/device/gauge.hpp"
#include "ballbar/device/transport.hpp"

namespace ballbar::device::gauge {

struct GaugeFaults {
    double not_ready_probability = 0;     ///< a request answered "no value yet"
    double out_of_range_probability = 0;  ///< a request answered "beyond the range"
    double no_reply_probability = 0;      ///< a request not answered at all
    double cut_off_probability = 0;       ///< only the first half of the reply is sent
    bool inch = false;                    ///< the gauge is set to inches
    bool low_battery = false;
};

struct GaugeEmulatorConfig {
    Kind kind = Kind::Sylvac;
    std::uint64_t seed = 1;
    double rate_hz = 20;            ///< simulated clock: each answered request takes 1/rate
    double resolution_mm = 0.0001;  ///< the digits it sends (inch mode: resolution_mm / 25.4 rounded)
    double noise_um = 0.1;          ///< 1 σ of one reading
    double offset_mm = 3.2105;      ///< what it reads when the bar is at its calibrated length
    double sign = +1;               ///< reading = offset + sign × bar displacement
    double range_mm = 12.5;         ///< |reading| beyond this: out of range
    std::string serial = "EMU-G0001";
    int modbus_slave = 1;
    GaugeFaults faults;
};

/// 13 Digimatic SPC nibbles for `value` (in mm, or inch when `inch`) with `decimals` digits.
std::array<std::uint8_t, 13> encode_spc_frame(double value, int decimals, bool inch);

/// CRC-16/MODBUS (poly 0xA001 reflected, init 0xFFFF); sent low byte first.
std::uint16_t modbus_crc(std::span<const std::uint8_t> data);

class GaugeEmulator final : public DeviceEndpoint {
  public:
    /// Bar displacement (mm, positive = longer) at `t_s` seconds of the gauge's clock.
    using Displacement = std::function<double(double t_s)>;
    explicit GaugeEmulator(GaugeEmulatorConfig config, Displacement displacement = {}, bool simulated_clock = false);

    // Serial protocols (Sylvac, Digimatic adaptor, Modbus RTU).
    void on_host_bytes(std::span<const std::uint8_t> data) override;
    std::size_t take_device_bytes(std::span<std::uint8_t> out) override;

    // USB-ITN.
    void control_out(std::uint8_t request, std::uint16_t value, std::span<const std::uint8_t> data);
    /// Returns the bytes of the data stage, or -1 to stall.
    int control_in(std::uint8_t request, std::uint16_t value, std::span<std::uint8_t> out);
    /// One interrupt-IN packet (at most 8 bytes); 0 when nothing is pending.
    std::size_t take_interrupt(std::span<std::uint8_t> out);

    /// The gauge's clock, µs: simulated (advanced by each answered request) or real time since creation.
    std::uint64_t now_us() const;
    /// Puts the bar in its calibrator (displacement 0) or back on the machine.
    void set_in_calibrator(bool in) { in_calibrator_ = in; }
    void set_faults(const GaugeFaults& f);
    const GaugeEmulatorConfig& config() const { return config_; }
    std::uint64_t requests() const { return requests_; }

  private:
    enum class Fault { None, NotReady, OutOfRange, NoReply, CutOff };
    Fault draw_fault();
    /// One value as the gauge reads it now, in its unit; false when beyond its range.
    bool sample_value(double& value, int& decimals);
    void tick();
    void send(std::deque<std::uint8_t>& q, const std::string& reply, Fault f);
    void on_sylvac_line(const std::string& line);
    void on_modbus_bytes();
    void itn_command(const std::string& line);

    GaugeEmulatorConfig config_;
    Displacement displacement_;
    bool simulated_;
    std::chrono::steady_clock::time_point start_;
    std::atomic<std::uint64_t> sim_us_{0};
    std::atomic<bool> in_calibrator_{false};
    mutable std::mutex m_;
    std::mt19937_64 rng_;
    std::normal_distribution<double> gauss_{0.0, 1.0};
    std::uniform_real_distribution<double> uniform_{0.0, 1.0};
    std::string line_;
    std::vector<std::uint8_t> rtu_;
    std::deque<std::uint8_t> out_, interrupt_;
    bool itn_initialised_ = false;
    std::uint64_t requests_ = 0;
    std::uint64_t release_us_ = 0;  ///< real-time clock: the pending reply is sent from then on
};

/// The USB-ITN's USB side wired straight to an emulator in this process (`ballbar demo --instrument
/// mitutoyo-itn`; the libusb path is tested under umockdev). Borrows `emulator`.
std::unique_ptr<ItnLink> make_emulated_itn_link(GaugeEmulator& emulator, std::string serial = "EMU-G0001");

/// A serial gauge emulator behind a pseudo-terminal, served by a thread until destroyed (a pulled cable).
class GaugePtyHost {
  public:
    explicit GaugePtyHost(GaugeEmulator& emulator);
    ~GaugePtyHost();
    GaugePtyHost(const GaugePtyHost&) = delete;
    GaugePtyHost& operator=(const GaugePtyHost&) = delete;
    /// The slave side: open it as sylvac:PATH, digimatic:PATH or modbus:PATH.
    const std::string& path() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ballbar::device::gauge
