// SPDX-License-Identifier: MIT
// What the API tests of `ballbar serve` share: a server on a free loopback port in the test's process,
// requests as the page makes them (cpp-httplib's client), waiting for the procedure's next question, and
// another process of the test (`ballbar emulate --pty`, `ballbar serve`) whose first output line it reads.
#pragma once

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "../scratch_dir.hpp"
#include "ballbar/webui/server.hpp"
// After Eigen (through the headers above): httplib.h brings <resolv.h>, whose `_res` macro breaks
// Eigen's product kernels when they come later.
#include <httplib.h>

namespace ballbar::test::webui {

using json = nlohmann::json;
using namespace std::chrono_literals;

/// A server on a free loopback port, serving on a thread of the test.
class Served {
  public:
    explicit Served(ballbar::webui::ServeOptions o) : server(std::move(o)) {
        port = server.bind();
        thread = std::thread([this] { server.run(); });
    }
    ~Served() {
        server.stop();
        thread.join();
    }
    Served(const Served&) = delete;
    Served& operator=(const Served&) = delete;
    httplib::Client client(const std::string& id = "page-1") const {
        httplib::Client c("127.0.0.1", port);
        c.set_read_timeout(30, 0);
        c.set_default_headers({{"X-Ballbar-Client", id}});
        return c;
    }
    ballbar::webui::Server server;
    int port = 0;
    std::thread thread;
};

inline ballbar::webui::ServeOptions options(const ScratchDir& dir) {
    ballbar::webui::ServeOptions o;
    o.port = 0;
    o.db_path = dir.file("sessions.db");
    return o;
}

inline json get_json(httplib::Client& c, const std::string& path) {
    auto r = c.Get(path.c_str());
    if (!r) throw std::runtime_error("no answer to GET " + path);
    if (r->status != 200) throw std::runtime_error("GET " + path + ": " + std::to_string(r->status) + " " + r->body);
    return json::parse(r->body);
}

inline httplib::Result post(httplib::Client& c, const std::string& path, const json& body) {
    return c.Post(path.c_str(), body.dump(), "application/json");
}

/// Waits until the procedure asks a question (its id) or has ended (0).
inline std::uint64_t next_question(httplib::Client& c, json& state, std::chrono::seconds within = 60s) {
    const auto until = std::chrono::steady_clock::now() + within;
    while (std::chrono::steady_clock::now() < until) {
        state = get_json(c, "/api/procedure");
        if (state["question"].is_object()) return state["question"]["id"].get<std::uint64_t>();
        if (!state["running"].get<bool>()) return 0;
        std::this_thread::sleep_for(20ms);
    }
    throw std::runtime_error("no question and no end within the time");
}

/// Answers question `q` with option `option`; throws when the server refuses.
inline void answer(httplib::Client& c, std::uint64_t q, std::size_t option = 0) {
    auto r = post(c, "/api/procedure/answer", {{"question", q}, {"option", option}});
    if (!r || r->status != 200) throw std::runtime_error("answer refused: " + (r ? r->body : std::string("no answer")));
}

/// Answers every question with its first option, as an operator clicking through; the final state.
inline json drive_to_end(httplib::Client& c, std::vector<std::string>* asked = nullptr) {
    json state;
    while (const auto q = next_question(c, state)) {
        if (asked) asked->push_back(state["question"]["what"].get<std::string>());
        answer(c, q);
    }
    return state;
}

/// Another process of the test, its standard output on a pipe; `first_line` is what it printed first
/// (`emulate --pty` prints its pty, `serve` the address to open). Interrupted (SIGINT) and reaped when
/// the test is done with it.
class Child {
  public:
    explicit Child(std::vector<std::string> args) {
        int fd[2];
        if (::pipe(fd) != 0) throw std::runtime_error("pipe failed");
        std::vector<char*> argv;
        for (auto& a : args) argv.push_back(a.data());
        argv.push_back(nullptr);
        pid_ = ::fork();
        if (pid_ == 0) {
            ::dup2(fd[1], STDOUT_FILENO);
            ::close(fd[0]);
            ::execv(argv[0], argv.data());
            ::_exit(127);
        }
        ::close(fd[1]);
        out_ = fd[0];
        char c = 0;
        while (::read(out_, &c, 1) == 1 && c != '\n') first_line += c;
    }
    ~Child() { stop(SIGINT); }
    Child(const Child&) = delete;
    Child& operator=(const Child&) = delete;
    /// Sends `signal` and waits for the exit; the exit status (waitpid's), or -1 when already reaped.
    int stop(int signal) {
        if (pid_ <= 0) return -1;
        ::kill(pid_, signal);
        int st = 0;
        ::waitpid(pid_, &st, 0);
        pid_ = -1;
        ::close(out_);
        return st;
    }
    std::string first_line;

  private:
    pid_t pid_ = -1;
    int out_ = -1;
};

}  // namespace ballbar::test::webui
