// SPDX-License-Identifier: MIT
// Ctrl-C for long-running commands: while an InterruptGuard lives, the first SIGINT or SIGTERM sets a
// flag instead of killing the process, so the command can store what it has and exit 3. The handler
// is installed without SA_RESTART, so a prompt or a read blocked in the kernel returns at once
// (EINTR), and resets itself: a second Ctrl-C ends the process the default way (the database is
// safe either way: a session left running is marked `interrupted` when the store is next opened).
#pragma once

#include <atomic>

namespace ballbar::app {

class InterruptGuard {
  public:
    InterruptGuard();
    ~InterruptGuard();  ///< restores the handlers that were there before
    InterruptGuard(const InterruptGuard&) = delete;
    InterruptGuard& operator=(const InterruptGuard&) = delete;

    /// Set by the first SIGINT/SIGTERM.
    static const std::atomic<bool>* flag();
    static bool requested() { return flag()->load(); }
    /// Raises the flag as a signal would: the operator's confirmed "abort" at a prompt.
    static void request();
};

}  // namespace ballbar::app
