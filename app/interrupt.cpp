// SPDX-License-Identifier: MIT
#include "interrupt.hpp"

#include <signal.h>

#include <cstring>

namespace ballbar::app {
namespace {

std::atomic<bool> g_interrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the flag is written from a signal handler");

struct sigaction g_old_int, g_old_term;

extern "C" void on_interrupt(int) {
    g_interrupted.store(true);
}

}  // namespace

InterruptGuard::InterruptGuard() {
    g_interrupted.store(false);
    struct sigaction sa;
    std::memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_interrupt;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESETHAND;  // no SA_RESTART: blocked reads and prompts return with EINTR
    ::sigaction(SIGINT, &sa, &g_old_int);
    ::sigaction(SIGTERM, &sa, &g_old_term);
}

InterruptGuard::~InterruptGuard() {
    ::sigaction(SIGINT, &g_old_int, nullptr);
    ::sigaction(SIGTERM, &g_old_term, nullptr);
}

void InterruptGuard::request() {
    g_interrupted.store(true);
}

const std::atomic<bool>* InterruptGuard::flag() {
    return &g_interrupted;
}

}  // namespace ballbar::app
