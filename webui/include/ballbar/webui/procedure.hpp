// SPDX-License-Identifier: MIT
// The one guided procedure a `ballbar serve` runs at a time, as the page sees it: the workflow layer's
// use cases (the SSM and circular demos, a measurement on a device URI, a resumed session) on a thread
// of their own, with an operator whose questions wait for a button pressed on the page. Its state is a
// JSON snapshot (docs/webui.md, "GET /api/procedure"), its live bar reading a separate counter so that a
// 50 Hz stream does not copy the whole state.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "ballbar/acquisition/interfaces.hpp"

namespace ballbar::webui {

/// A request the API refuses: its HTTP status and the message the page shows.
class ApiError : public std::runtime_error {
  public:
    ApiError(int status, const std::string& message) : std::runtime_error(message), status_(status) {}
    int status() const { return status_; }

  private:
    int status_;
};

/// The live bar reading: what a viewer's stream sends at up to 50 Hz.
struct LiveReading {
    std::uint64_t seq = 0;  ///< changes with every new reading
    double bar_mm = 0;
    double expected_mm = 0;
    double range_mm = 0;  ///< the transducer's range (±) around its zero; 0: the instrument does not say
    bool out_of_range = false;
    double fill = 0;  ///< 0..1 of the averaging window (SSM)
};

class Procedure {
  public:
    /// `db_path`: the database every procedure stores into (a store of its own on its thread).
    explicit Procedure(std::string db_path);
    ~Procedure();  ///< stops a running procedure (keeping what it measured) and waits for it
    Procedure(const Procedure&) = delete;
    Procedure& operator=(const Procedure&) = delete;

    /// Starts a procedure for `client` (who then steers it). `request` (docs/webui.md, "POST
    /// /api/procedure"): {"procedure": "ssm"|"circular", "demo": true, "machine", "plane", "device",
    /// "resume", "seed"}. ApiError 409 when one runs, 400 for a bad request.
    nlohmann::json start(const nlohmann::json& request, const std::string& client);
    /// Answers question `question` with option `option`. ApiError 409 for a question no longer asked
    /// (answered already, or never), 403 when `client` may not steer, 400 for an option out of range.
    void answer(std::uint64_t question, std::size_t option, const std::string& client);
    /// Stops the procedure: it ends interrupted and resumable, keeping every point and sample it stored.
    void stop(const std::string& client);
    /// Stops whatever runs and waits for its thread (server shutdown).
    void shutdown();

    /// The state as `client` sees it ("you_steer": whether its buttons count).
    nlohmann::json snapshot(const std::string& client = {}) const;
    std::uint64_t version() const;
    LiveReading live() const;
    /// Waits up to `timeout` for a state after `version`. A new live reading wakes nobody (at 1 kHz it
    /// would wake every stream a thousand times a second): a stream looks at live() on its own tick.
    void wait_change(std::uint64_t version, std::chrono::milliseconds timeout) const;

    /// A viewer's event stream opened or closed. A client that started the procedure steers it; when it
    /// has no stream open (its browser closed), the next client that steers takes over.
    void viewer(const std::string& client, bool open);
    std::size_t viewers() const;

    /// The operator the procedures talk to: its questions wait for the page's buttons, its progress is
    /// the live reading. A procedure's thread uses it; so does the stream benchmark (bench/webui).
    class WebOperator;
    acquisition::Operator& web_operator();

  private:
    struct Question {
        std::uint64_t id = 0;
        std::string kind;  ///< confirm, choose, point-failed, acknowledge
        std::string what;
        std::string prompt;
        std::vector<std::string> options;
        std::string not_yet;  ///< a button that answers nothing ("Not yet"): empty when none
        int step = 0;
    };
    void bump();                                   // under mu_
    void log(const std::string& text);             // under mu_
    void set_step(int step);                       // under mu_
    void check_driver(const std::string& client);  // under mu_
    std::size_t ask(Question q);                   // SIZE_MAX when stopped
    void run(nlohmann::json request);
    void finish(const std::string& state, const std::string& message);

    const std::string db_path_;
    mutable std::mutex mu_;
    mutable std::condition_variable changed_;  // state, live reading, answer, stop
    std::uint64_t version_ = 1;
    LiveReading live_;
    std::atomic<bool> stop_{false};
    bool running_ = false;
    std::thread thread_;
    std::string driver_;
    std::map<std::string, int> streams_;  // client → open event streams
    std::uint64_t question_seq_ = 0;
    std::optional<Question> question_;
    std::optional<std::size_t> answer_;
    nlohmann::json state_;  // what snapshot() adds the question to
    std::deque<nlohmann::json> log_;
    std::chrono::steady_clock::time_point started_;
    std::unique_ptr<WebOperator> operator_;
};

}  // namespace ballbar::webui
