// SPDX-License-Identifier: MIT
// The instrument's link as the guided procedures use it — the SSM session (session.cpp) and the
// circular one (circular_session.cpp): the reference set with the operator, the stream started and
// stopped, the link got back after it dropped. How a session ends stays the session's: it gives
// `check_stop` (throws when the operator stopped it) and `give_up` (ends it interrupted, resumable;
// never returns).
#pragma once

#include <chrono>
#include <functional>
#include <string>

#include "ballbar/acquisition/interfaces.hpp"

namespace ballbar::acquisition::detail {

class InstrumentLink {
  public:
    struct Settings {
        std::chrono::milliseconds read_timeout{200};
        int max_reconnect_attempts = 600;  ///< each `read_timeout` long
        /// How often the operator is told, while waiting for the instrument, how long is left.
        std::chrono::milliseconds note_every{10000};
    };
    using CheckStop = std::function<void()>;
    using GiveUp = std::function<void(const std::string& reason)>;

    InstrumentLink(SampleSource& source, Operator& op, Settings settings, CheckStop check_stop, GiveUp give_up);

    /// Asks the operator to put the bar in its calibrator (again, or stop) and sets the reference; a
    /// reference that fails (the link dropped right after it came back) is tried again after getting the
    /// link back, a few times.
    void reference();
    /// Reconnects until the instrument is back (identified, not streaming), for at most
    /// max_reconnect_attempts × read_timeout of wall time (an instrument that is there but does not
    /// answer makes each attempt last its own reply timeouts, so the attempts alone bound nothing),
    /// telling the operator the bound at the start and the time left every `note_every`; then gives up.
    void wait_for_instrument();
    /// Starts the stream unless it runs; a start that fails gets the link back and re-references first.
    /// True when it was started now.
    bool stream_on();
    /// Stops the stream if it runs; a link that broke while stopping shows at the next start.
    void stream_off();
    bool streaming() const { return streaming_; }
    /// The link dropped: the stream is gone with it.
    void lost() { streaming_ = false; }

  private:
    [[noreturn]] void fail(const std::string& reason);

    SampleSource& source_;
    Operator& op_;
    Settings settings_;
    CheckStop check_stop_;
    GiveUp give_up_;
    bool streaming_ = false;
};

}  // namespace ballbar::acquisition::detail
