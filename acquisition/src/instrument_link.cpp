// SPDX-License-Identifier: MIT
#include "instrument_link.hpp"

#include <stdexcept>
#include <utility>

namespace ballbar::acquisition::detail {
namespace {

/// How often a start or a reference that failed is tried again after getting the link back.
constexpr int kLinkRetries = 3;

}  // namespace

InstrumentLink::InstrumentLink(SampleSource& source, Operator& op, Settings settings, CheckStop check_stop,
                               GiveUp give_up)
    : source_(source), op_(op), settings_(settings), check_stop_(std::move(check_stop)), give_up_(std::move(give_up)) {}

void InstrumentLink::fail(const std::string& reason) {
    give_up_(reason);
    throw std::logic_error("InstrumentLink: give_up returned");  // it ends the session by throwing
}

void InstrumentLink::reference() {
    for (;;) {
        check_stop_();
        if (op_.confirm("reference", "Put the bar in its calibrator to set the reference (zero). Ready?")) break;
        const std::size_t c = op_.choose({"reference-declined",
                                          "The instrument must be referenced before it measures. Ask again, or stop "
                                          "the session (resumable)?",
                                          {"again", "stop"},
                                          0});
        if (c == 1) fail("reference not set");
    }
    for (int attempt = 1;; ++attempt) {
        try {
            source_.set_reference();
            return;
        } catch (const SourceError& err) {
            // No answer: the link may have dropped right after it came back. Get it back and try again
            // (the bar is still in its calibrator); give up like a lost instrument.
            if (attempt >= kLinkRetries) fail(std::string("setting the reference failed: ") + err.what());
            op_.message(std::string("Setting the reference failed (") + err.what() + "): reconnecting.");
            wait_for_instrument();
        }
    }
}

void InstrumentLink::wait_for_instrument() {
    using clock = std::chrono::steady_clock;
    const auto bound = settings_.read_timeout * settings_.max_reconnect_attempts;
    const auto start = clock::now();
    auto next_note = start + settings_.note_every;
    auto whole_s = [](clock::duration d) {
        return std::to_string(
            std::chrono::duration_cast<std::chrono::seconds>(d + std::chrono::milliseconds(500)).count());
    };
    op_.message("Waiting for the instrument to answer (at most " + whole_s(bound) +
                " s; then the session stops, resumable).");
    op_.instrument_lost(std::chrono::duration<double>(bound).count());
    for (int i = 0;; ++i) {
        const auto waited = clock::now() - start;
        if (i >= settings_.max_reconnect_attempts || waited >= bound)
            fail("the instrument did not come back within " + whole_s(waited) + " s");
        check_stop_();
        op_.instrument_waiting(std::chrono::duration<double>(bound - waited).count());
        bool back = false;
        try {
            back = source_.reconnect(settings_.read_timeout);
        } catch (const SourceError& err) {
            fail(std::string("the instrument came back unusable: ") + err.what());
        }
        if (back) {
            op_.instrument_back();
            return;
        }
        if (const auto now = clock::now(); now >= next_note && now - start < bound) {
            op_.message("Still no answer from the instrument: " + whole_s(bound - (now - start)) +
                        " s left before the session stops (resumable).");
            next_note = now + settings_.note_every;
        }
    }
}

bool InstrumentLink::stream_on() {
    if (streaming_) return false;
    for (int attempt = 1;; ++attempt) {
        try {
            source_.start();
            break;
        } catch (const SourceError& err) {
            // A link that broke again between its reconnect and this start (a cable still loose): get it
            // back and re-reference before streaming, as after any loss; give up like a lost instrument.
            if (attempt >= kLinkRetries) fail(std::string("the instrument does not stream: ") + err.what());
            op_.message(std::string("The instrument does not stream (") + err.what() + "): reconnecting.");
            wait_for_instrument();
            reference();
        }
    }
    streaming_ = true;
    return true;
}

void InstrumentLink::stream_off() {
    if (!streaming_) return;
    streaming_ = false;
    try {
        source_.stop();
    } catch (const SourceError&) {
        // A link that broke while stopping shows at the next start.
    }
}

}  // namespace ballbar::acquisition::detail
