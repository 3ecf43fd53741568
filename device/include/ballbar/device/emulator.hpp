// SPDX-License-Identifier: MIT
// The emulated instrument: the device side of protocol v1 (docs/protocol.md) for a simulated ball-bar
// on a simulated five-axis machine (sim_machine.hpp). It runs on a simulated clock that its host
// advances (advance_to): as fast as possible in tests, in real time behind a pty or a TCP socket.
// Deterministic for a given seed. Configured from JSON (docs/emulator.md). Not thread-safe: one host
// drives it; the machine inside may be commanded from other threads.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <random>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/analysis/nc_program.hpp"
#include "ballbar/device/continuous_machine.hpp"
#include "ballbar/device/protocol.hpp"
#include "ballbar/device/sim_machine.hpp"
#include "ballbar/device/transport.hpp"

namespace ballbar::device {

struct InstrumentModel {
    std::string model = "BB-1E";
    std::string serial = "EMU00001";
    std::string firmware = "1.0.0";
    double calibrated_length_mm = 150.0;
    std::string calibration_date = "2026-01-15";  ///< of the length calibration (IdentifyReply); "" = not told
    double noise_um = 0.25;                       ///< transducer noise (1 σ) of one reading, before averaging
    double zero_offset_um = 23.7;                 ///< transducer zero error until SetReference
    std::uint16_t sample_rate_hz = 1000;
    std::uint8_t averaging = 1;
    double temp_start_C = 20.3;
    double temp_drift_C_per_h = 0.8;
    double temp_ripple_C = 0.05;
    double temp_ripple_period_s = 300;
    double battery_start_pct = 98;
    double battery_drain_pct_per_h = 6;
    double watchdog_s = 0;  ///< stop streaming after this long without a host frame; 0 = never
};

/// Faults the emulator injects (all off by default). Times are on the emulator's clock.
struct FaultConfig {
    double drop_frame_probability = 0;    ///< a stream frame is not sent (its sequence number is used)
    double corrupt_byte_probability = 0;  ///< a sent byte gets one bit flipped
    double stall_at_s = -1;               ///< the device goes silent at this time (< 0: never) ...
    double stall_s = 0;                   ///< ... for this long; its output is held and then sent at once
    double disconnect_at_s = -1;          ///< the link goes away at this time (< 0: never) ...
    double disconnect_s = 0;              ///< ... and comes back after this long (streaming stopped)
    double reply_delay_ms = 0;            ///< replies are sent this late
    double replay_frame_probability = 0;  ///< a stream frame is sent twice (same sequence number)
    // The machine's side (applied by whoever runs its programs: the demo's operator).
    double start_delay_s = 0;   ///< each program starts this long after the operator is told to start it
    double feed_override = 1;   ///< feed override of the machine's G1 moves (G4 dwells keep their time)
    double answer_delay_s = 0;  ///< the operator presses cycle start this long after the machine reaches a stop
};

struct NcSource {
    std::string text;
    analysis::NcDialect dialect = analysis::NcDialect::Fanuc;
    /// Runs from power-on (true), or waits for cycle start (false): each Start request of the host is
    /// the operator's cycle start (docs/emulator.md).
    bool power_on = false;
    /// When set, the program is read again from this file at a cycle start that begins a program (the
    /// operator loaded a new one); a missing or unreadable file keeps the last text.
    std::string file;
};

struct EmulatorConfig {
    std::uint64_t seed = 1;
    /// "time": "simulated": an in-process emulator (`emulator:CONFIG`) runs as fast as its host reads, its
    /// timeouts counted on its own clock (CI: a session takes the CPU's time, not the machine's);
    /// "real" (the default) follows the wall clock. Hosts that serve a pty or TCP choose their own pacing.
    bool simulated_time = false;
    InstrumentModel instrument;
    MachineSetup machine;
    std::optional<NcSource> program;  ///< the machine's program (power-on or cycle start)
    FaultConfig faults;
    /// Continuous motion of the linear axes (the circular test, docs/emulator.md): when set, programs run
    /// on a ContinuousMachine (arcs, servo lag, the trace format's effects) and the bar measures it.
    std::optional<ContinuousErrors> continuous;
};

/// Parses the JSON configuration (docs/emulator.md). Unknown keys and bad values throw
/// std::invalid_argument naming the key. `base_dir` resolves a relative "program.file".
EmulatorConfig parse_emulator_config(std::string_view json_text, const std::string& base_dir = ".");
EmulatorConfig load_emulator_config(const std::string& path);

class Emulator : public DeviceEndpoint {
  public:
    explicit Emulator(EmulatorConfig config);

    // DeviceEndpoint
    void on_host_bytes(std::span<const std::uint8_t> data) override;
    std::size_t take_device_bytes(std::span<std::uint8_t> out) override;

    /// The host side of the link went away (USB unplug, TCP client gone): a bus-powered instrument
    /// loses power; it stops streaming, drops queued output and forgets a partial request.
    void host_link_lost();
    /// Moves the simulated clock forward (never back) and produces what the device would have sent.
    void advance_to(std::uint64_t t_us);
    std::uint64_t now_us() const { return now_us_; }
    /// False during a simulated disconnect: the host link should report DeviceError{Disconnected}.
    bool connected() const { return connected_; }
    /// Incremented each time the link comes back.
    std::uint64_t connection_epoch() const { return epoch_; }
    /// Device→host bytes waiting to be taken.
    std::size_t pending_output() const { return out_.size() - out_head_; }

    SimulatedMachine& machine() { return machine_; }
    /// The continuous machine (configured with "continuous"), else nullptr.
    ContinuousMachine* continuous() { return continuous_.get(); }
    const ContinuousMachine* continuous() const { return continuous_.get(); }
    const SimulatedMachine& machine() const { return machine_; }
    const EmulatorConfig& config() const { return config_; }
    FaultConfig& faults() { return config_.faults; }
    bool streaming() const { return streaming_; }
    /// The watchdog (InstrumentConfig::watchdog_s) counts the host's silence on the emulator's clock,
    /// which is real time on a real instrument. A host that runs that clock faster than real time
    /// (Pacing::Simulated) counts the silence on the wall clock instead: it turns the emulator's own
    /// count off here and calls watchdog_expired() when its count runs out.
    void set_external_watchdog(bool on) { external_watchdog_ = on; }
    /// The host has been silent for watchdog_s by the external count: stop streaming as the watchdog would.
    void watchdog_expired();
    double bar_temp_C(std::uint64_t t_us) const;

    struct Counters {
        std::uint64_t samples = 0;          ///< generated while streaming
        std::uint64_t stream_frames = 0;    ///< sent
        std::uint64_t dropped_frames = 0;   ///< by fault injection or overrun
        std::uint64_t replayed_frames = 0;  ///< sent twice by fault injection
        std::uint64_t cycle_starts = 0;     ///< host Start requests taken as cycle start
        std::uint64_t programs_started = 0;
        std::uint64_t corrupted_bytes = 0;
        std::uint64_t requests = 0;
        std::uint64_t invalid_host_frames = 0;
    };
    const Counters& counters() const { return counters_; }

  private:
    struct Delayed {
        std::uint64_t release_us;
        protocol::FrameBuffer bytes;
        std::size_t size;
    };
    void handle(const protocol::FrameView& frame);
    void cycle_start();
    void reply(const protocol::FrameBuffer& buf, std::size_t n);
    void emit(const protocol::FrameBuffer& buf, std::size_t n);
    void produce_samples_until(std::uint64_t t_us);
    void flush_stream();
    void go_disconnected();
    protocol::StatusReply status() const;
    double gaussian();
    double uniform();

    EmulatorConfig config_;
    SimulatedMachine machine_;
    std::unique_ptr<ContinuousMachine> continuous_;
    std::mt19937_64 rng_;
    protocol::Decoder decoder_;
    std::vector<std::uint8_t> out_;
    std::size_t out_head_ = 0;
    std::deque<Delayed> delayed_;
    std::vector<std::uint8_t> stalled_input_;
    std::uint64_t now_us_ = 0;
    std::uint64_t last_host_us_ = 0;
    bool external_watchdog_ = false;
    bool connected_ = true;
    bool disconnect_done_ = false;
    std::uint64_t epoch_ = 0;
    // Instrument state.
    bool streaming_ = false;
    bool referenced_ = false;
    bool overrun_ = false;
    std::uint16_t rate_hz_;
    std::uint8_t averaging_;
    std::uint16_t stream_seq_ = 0;
    std::uint64_t stream_start_ns_ = 0;
    std::uint64_t sample_index_ = 0;  ///< next sample since Start
    std::uint32_t period_ns_ = 1'000'000;
    protocol::StreamFrame pending_{};
    std::uint64_t pending_first_us_ = 0;
    Counters counters_;
    bool program_started_ = false;
    std::string loaded_program_;
};

}  // namespace ballbar::device
