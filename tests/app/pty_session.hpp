// SPDX-License-Identifier: MIT
// The `ballbar` executable on a pseudo-terminal (forkpty), driven as an operator at a terminal drives it:
// wait until a text appears on the screen, type an answer, read the exit status.
#pragma once

#include <poll.h>
#include <pty.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

namespace ballbar::test {

class PtySession {
  public:
    /// Runs BALLBAR_EXE with `args` on a new terminal (colour on: NO_COLOR unset).
    explicit PtySession(std::vector<std::string> args) {
        args.insert(args.begin(), BALLBAR_EXE);
        std::vector<char*> argv;
        for (auto& a : args) argv.push_back(a.data());
        argv.push_back(nullptr);
        pid_ = ::forkpty(&master_, nullptr, nullptr, nullptr);
        if (pid_ < 0) throw std::runtime_error("forkpty failed");
        if (pid_ == 0) {
            ::unsetenv("NO_COLOR");
            ::execv(argv[0], argv.data());
            ::_exit(127);
        }
    }
    ~PtySession() {
        if (pid_ > 0) {
            ::kill(pid_, SIGKILL);
            ::waitpid(pid_, nullptr, 0);
        }
        if (master_ >= 0) ::close(master_);
    }
    PtySession(const PtySession&) = delete;
    PtySession& operator=(const PtySession&) = delete;

    /// Waits until `text` appears on the screen after position `from` (the end of what was matched so
    /// far when omitted); true when it did within `timeout`. The matched end becomes the new position.
    bool wait_for(const std::string& text, std::chrono::seconds timeout = std::chrono::seconds(60)) {
        const auto until = std::chrono::steady_clock::now() + timeout;
        for (;;) {
            if (const auto at = screen.find(text, pos_); at != std::string::npos) {
                pos_ = at + text.size();
                return true;
            }
            if (std::chrono::steady_clock::now() > until || !read_some(200)) return false;
        }
    }
    /// Reads what comes for `ms` milliseconds (or until the terminal closes).
    void settle(int ms) {
        const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
        while (std::chrono::steady_clock::now() < until && read_some(50)) {
        }
    }
    /// What the program wrote since the last match.
    std::string unmatched() const { return screen.substr(pos_); }
    void type(const std::string& keys) {
        if (::write(master_, keys.data(), keys.size()) != static_cast<ssize_t>(keys.size()))
            throw std::runtime_error("cannot type on the terminal");
    }
    /// Reads to the end and returns the exit code (-1: killed after `timeout`, or by a signal).
    int exit_code(std::chrono::seconds timeout = std::chrono::seconds(60)) {
        const auto until = std::chrono::steady_clock::now() + timeout;
        while (std::chrono::steady_clock::now() < until && read_some(200)) {
        }
        int st = 0;
        while (::waitpid(pid_, &st, WNOHANG) == 0) {
            if (std::chrono::steady_clock::now() > until) {
                ::kill(pid_, SIGKILL);
                ::waitpid(pid_, &st, 0);
                pid_ = -1;
                return -1;
            }
            ::usleep(20000);
        }
        pid_ = -1;
        return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    }
    std::string screen;

  private:
    /// False once the terminal is closed (the program ended).
    bool read_some(int timeout_ms) {
        pollfd pfd{master_, POLLIN, 0};
        if (::poll(&pfd, 1, timeout_ms) <= 0) return true;
        std::array<char, 4096> buf{};
        const ssize_t n = ::read(master_, buf.data(), buf.size());
        if (n <= 0) return false;
        screen.append(buf.data(), static_cast<std::size_t>(n));
        return true;
    }
    pid_t pid_ = -1;
    int master_ = -1;
    std::size_t pos_ = 0;
};

}  // namespace ballbar::test
