// SPDX-License-Identifier: MIT
// The instrument driver: protocol v1 over any Transport. Requests (identify, status, configure, set
// reference, start/stop, heartbeat) with timeouts and retries; stream frames decoded into a bounded,
// preallocated sample queue. Lost frames are counted from the stream sequence numbers and the first
// sample after any loss carries kSampleAfterGap: a gap is never papered over. A frame that comes again
// (an older sequence number, device time not newer than what was accepted) is skipped and counted as
// replayed, never stored twice; a frame of another protocol version is skipped and counted.
//
// Threading: one thread calls the Instrument (requests and poll()); SampleQueue is single-producer /
// single-consumer, so another thread may drain it with pop().
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ballbar/analysis/sample.hpp"
#include "ballbar/device/protocol.hpp"
#include "ballbar/device/transport.hpp"

namespace ballbar::device {

/// Host-side sample flag (not on the wire): samples were lost right before this one (device frames
/// missing, corrupt frames dropped, or this queue overflowing).
using analysis::kSampleAfterGap;  // analysis/sample.hpp: host-only flag of the first sample after a gap

struct InstrumentInfo {
    int protocol_version = 0;
    std::string model, serial, firmware;
    double calibrated_length_mm = 0;
    std::string calibration_date;  ///< ISO 8601 date of the length calibration; empty = not told
    double resolution_um = 0;
    double range_mm = 0;
};

struct InstrumentStatus {
    int battery_pct = 0;
    double battery_V = 0;
    double bar_temp_C = 0;
    std::uint16_t error_flags = 0;  ///< protocol::StatusFlags
    bool streaming = false;
    int sample_rate_hz = 0;
    int averaging = 0;
    bool referenced = false;
};

struct StreamStats {
    std::uint64_t frames = 0;           ///< stream frames accepted
    std::uint64_t samples = 0;          ///< samples queued
    std::uint64_t lost_frames = 0;      ///< from sequence-number gaps
    std::uint64_t gaps = 0;             ///< how many times a gap was seen
    std::uint64_t queue_drops = 0;      ///< samples lost because the queue was full
    std::uint64_t invalid_frames = 0;   ///< rejected by the decoder (CRC, framing)
    std::uint64_t stale_replies = 0;    ///< replies to requests we no longer wait for
    std::uint64_t stale_frames = 0;     ///< stream frames of an earlier session, before StartReply
    std::uint64_t replayed_frames = 0;  ///< stream frames seen again (an older seq, no newer device time): skipped
    std::uint64_t unknown_version_frames = 0;  ///< frames of another protocol version: skipped
    int unknown_version = 0;                   ///< the version of the last of them
};

/// Bounded single-producer/single-consumer ring of samples, allocated once.
class SampleQueue {
  public:
    explicit SampleQueue(std::size_t capacity);
    bool push(const analysis::BarSample& s);  ///< false when full
    std::size_t pop(std::span<analysis::BarSample> out);
    std::size_t size() const;
    std::size_t capacity() const { return mask_ + 1; }

  private:
    std::vector<analysis::BarSample> ring_;
    std::size_t mask_;
    std::atomic<std::size_t> head_{0};  ///< next to pop
    std::atomic<std::size_t> tail_{0};  ///< next to push
};

struct InstrumentOptions {
    std::chrono::milliseconds reply_timeout{500};  ///< per attempt
    int attempts = 3;
    std::size_t queue_capacity = 1u << 16;
    std::chrono::milliseconds heartbeat_interval{1000};
};

class Instrument {
  public:
    explicit Instrument(std::unique_ptr<Transport> transport, InstrumentOptions options = {});

    /// Throws DeviceError: Timeout (no answer after all attempts), Protocol (an error reply or an
    /// unacceptable answer), Disconnected, Io, ...
    const InstrumentInfo& identify();
    InstrumentStatus status();
    void configure(int sample_rate_hz, int averaging);
    void set_reference();
    void start_streaming();
    void stop_streaming();
    /// Returns the device's uptime in µs.
    std::uint64_t heartbeat();

    /// Reads what the link has within `timeout` (one read), queues samples; sends the keep-alive
    /// heartbeat while streaming. Returns the number of samples queued.
    std::size_t poll(std::chrono::milliseconds timeout);
    /// Takes up to out.size() samples from the queue.
    std::size_t read_samples(std::span<analysis::BarSample> out) { return queue_.pop(out); }

    SampleQueue& queue() { return queue_; }
    const StreamStats& stats() const { return stats_; }
    const std::optional<InstrumentInfo>& info() const { return info_; }
    bool streaming() const { return streaming_; }
    Transport& transport() { return *transport_; }

  private:
    struct Reply {
        protocol::MsgType type;
        std::array<std::uint8_t, protocol::kMaxBodySize> body;
        std::size_t size;
        std::span<const std::uint8_t> span() const { return {body.data(), size}; }
    };
    Reply request(protocol::MsgType type, std::span<const std::uint8_t> body);
    std::size_t pump(std::chrono::milliseconds timeout);  ///< one read; returns the bytes read
    void on_frame(const protocol::FrameView& frame);
    void on_stream(const protocol::FrameView& frame);
    [[noreturn]] void protocol_error(const std::string& what) const;

    std::unique_ptr<Transport> transport_;
    InstrumentOptions options_;
    SampleQueue queue_;
    protocol::Decoder decoder_;
    std::array<std::uint8_t, 16384> rx_{};
    protocol::StreamFrame frame_{};
    std::optional<InstrumentInfo> info_;
    StreamStats stats_;
    std::uint16_t next_seq_ = 1;
    std::optional<std::uint16_t> waiting_seq_;
    std::optional<Reply> reply_;
    bool streaming_ = false;
    bool start_pending_ = false;
    std::uint16_t expected_stream_seq_ = 0;
    bool have_stream_frame_ = false;       ///< a frame of the current stream was accepted
    std::uint64_t last_stream_t0_us_ = 0;  ///< its t0
    bool gap_pending_ = false;
    std::uint64_t host_seq_ = 0;
    std::uint32_t heartbeat_token_ = 0;
    std::chrono::steady_clock::time_point last_heartbeat_{};
};

}  // namespace ballbar::device
