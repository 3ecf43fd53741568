// SPDX-License-Identifier: MIT
// Decoder throughput in samples/s: full 13-sample stream frames through the decoder and parse_stream
// (the codec alone), and through the driver into its sample queue (codec + bookkeeping + queue).
#include <benchmark/benchmark.h>

#include <cstring>
#include <vector>

#include "ballbar/device/instrument.hpp"
#include "ballbar/device/protocol.hpp"

using namespace ballbar::device;
namespace p = ballbar::device::protocol;

namespace {

/// One full cycle of stream sequence numbers (65536 frames × 13 samples), so it can be replayed
/// end to end without a gap.
const std::vector<std::uint8_t>& stream_bytes() {
    static const std::vector<std::uint8_t> bytes = [] {
        std::vector<std::uint8_t> out;
        out.reserve(65536 * p::kMaxFrameSize);
        p::StreamFrame f;
        f.period_ns = 200'000;
        f.count = p::kMaxSamplesPerFrame;
        std::uint32_t x = 12345;
        for (std::uint32_t seq = 0; seq < 65536; ++seq) {
            f.t0_us = 1'000'000 + seq * 2600ull;
            f.bar_temp_cC = static_cast<std::int16_t>(2000 + seq % 50);
            for (auto& s : f.samples) {
                x = x * 1664525u + 1013904223u;
                s.displacement = static_cast<std::int16_t>(static_cast<int>(x >> 16) % 20001 - 10000);
                s.flags = 0;
            }
            p::FrameBuffer buf{};
            const std::size_t n = p::encode(f, static_cast<std::uint16_t>(seq), buf);
            out.insert(out.end(), buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(n));
        }
        return out;
    }();
    return bytes;
}

void BM_DecodeStreamFrames(benchmark::State& state) {
    const auto& bytes = stream_bytes();
    const auto chunk = static_cast<std::size_t>(state.range(0));
    p::Decoder dec;
    p::StreamFrame frame;
    std::int64_t samples = 0;
    std::int64_t checksum = 0;
    for (auto _ : state) {
        for (std::size_t at = 0; at < bytes.size(); at += chunk) {
            std::span<const std::uint8_t> in{bytes.data() + at, std::min(chunk, bytes.size() - at)};
            while (true) {
                const auto r = dec.next(in);
                if (r.status == p::DecodeStatus::NeedMore) break;
                if (r.status == p::DecodeStatus::Frame && p::parse_stream(r.frame.body, frame)) {
                    for (std::size_t i = 0; i < frame.count; ++i) checksum += frame.samples[i].displacement;
                    samples += frame.count;
                }
            }
        }
    }
    benchmark::DoNotOptimize(checksum);
    if (dec.invalid() != 0) state.SkipWithError("invalid frames");
    state.SetItemsProcessed(samples);
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(bytes.size()));
}
// Read sizes: a USB full-speed packet, a typical tty read, a large read.
BENCHMARK(BM_DecodeStreamFrames)->Arg(64)->Arg(4096)->Arg(1 << 20)->Unit(benchmark::kMillisecond);

/// A transport that replays the stream cycle (after answering Start).
class ReplayTransport final : public Transport {
  public:
    void write(std::span<const std::uint8_t> data, std::chrono::milliseconds) override {
        p::Decoder d;
        auto r = d.next(data);
        if (r.status == p::DecodeStatus::Frame && r.frame.type == p::MsgType::Start) {
            reply_size_ = p::encode_empty(p::MsgType::StartReply, r.frame.seq, reply_);
        }
    }
    std::size_t read(std::span<std::uint8_t> out, std::chrono::milliseconds) override {
        if (reply_size_ > 0) {
            std::memcpy(out.data(), reply_.data(), reply_size_);
            return std::exchange(reply_size_, 0);
        }
        const auto& bytes = stream_bytes();
        const std::size_t n = std::min(out.size(), bytes.size() - at_);
        std::memcpy(out.data(), bytes.data() + at_, n);
        at_ = (at_ + n) % bytes.size();
        return n;
    }
    std::string uri() const override { return "replay:"; }

  private:
    p::FrameBuffer reply_{};
    std::size_t reply_size_ = 0;
    std::size_t at_ = 0;
};

void BM_DriverIngest(benchmark::State& state) {
    InstrumentOptions opt;
    opt.heartbeat_interval = std::chrono::hours(1);
    Instrument inst(std::make_unique<ReplayTransport>(), opt);
    inst.start_streaming();
    std::vector<ballbar::analysis::BarSample> out(8192);
    std::int64_t samples = 0;
    for (auto _ : state) {
        inst.poll(std::chrono::milliseconds(0));
        samples += static_cast<std::int64_t>(inst.read_samples(out));
    }
    if (inst.stats().lost_frames != 0 || inst.stats().queue_drops != 0) state.SkipWithError("lost samples");
    state.SetItemsProcessed(samples);
}
BENCHMARK(BM_DriverIngest);

}  // namespace
