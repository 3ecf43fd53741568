// SPDX-License-Identifier: MIT
// `ballbar serve`: the guided procedures, the sessions and their reports as a local web page, served by
// the program itself (cpp-httplib; the page is compiled in, nothing comes from the internet). The page
// and any script use the same JSON API (docs/webui.md); the procedures are the workflow layer's, run by
// webui::Procedure. Safe by default: 127.0.0.1, a token on any other address, no cross-origin writes,
// no file served but what the server generates, one screen steering a procedure and any number watching.
#pragma once

#include <atomic>
#include <memory>
#include <string>

#include "ballbar/webui/procedure.hpp"

namespace ballbar::webui {

struct ServeOptions {
    std::string host = "127.0.0.1";
    int port = 8230;               ///< 0: any free port (the bound one is bind()'s answer)
    std::string token;             ///< when set, every request must carry it (Authorization: Bearer, or ?token=)
    std::string db_path;           ///< the database the sessions are in and new ones go to
    std::string software_version;  ///< in the reports
    int max_viewers = 64;          ///< event streams open at once; more are refused (503)
};

/// True for 127.0.0.0/8, ::1 and "localhost": an address no other machine reaches.
bool is_loopback(const std::string& host);

/// A new random token (128 bits, hex), from the kernel's random source.
std::string random_token();

class Server {
  public:
    explicit Server(ServeOptions options);
    ~Server();  ///< stops (as stop()) and waits
    Server(const Server&) = delete;
    Server& operator=(const Server&) = delete;

    /// Binds the address; returns the port. Error (bad input) when the address or port cannot be bound
    /// (in use: a second server fails here rather than sharing the port).
    int bind();
    /// Serves until stop(). Returns once every request has ended.
    void run();
    /// From any thread (a signal's): a running procedure stops keeping what it measured (resumable),
    /// its thread is joined, then the server stops.
    void stop();

    Procedure& procedure();

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ballbar::webui
