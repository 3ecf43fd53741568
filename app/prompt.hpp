// SPDX-License-Identifier: MIT
// The operator's answers at a terminal, read so that none ends a session by accident:
//   - keys typed while the machine ran answer nothing: typed-ahead input is discarded before each
//     question (on a terminal);
//   - every prompt understands abort (quit, stop: asked twice, then the session stops as on Ctrl-C,
//     keeping what it measured, resumable) and help; nothing else ends a session;
//   - "no" at a "Ready?" question means "not yet": it is asked again;
//   - an answer is a whole option or the start of exactly one ("a" where accept and abort are options
//     is refused, saying both).
#pragma once

#include <cstddef>
#include <functional>
#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace ballbar::app {

class Prompter {
  public:
    /// `discard_typed_ahead`: `in` is the terminal (its pending input is flushed before each question);
    /// `bold`: prompts in bold; `abort`: what an operator's confirmed abort does (raise the stop flag of
    /// the session, as Ctrl-C does).
    Prompter(std::istream& in, std::ostream& out, bool discard_typed_ahead, bool bold, std::function<void()> abort);

    /// A "Ready?" question: true on yes. "no"/"not yet" ask again; false on a confirmed abort (stopped)
    /// or when the input ends.
    bool ready(std::string_view prompt);
    /// One of `options` (their index), abort understood (the "abort" or "stop" option when there is one,
    /// else the stop flag and nullopt); nullopt when the input ends.
    std::optional<std::size_t> choose(std::string_view prompt, const std::vector<std::string>& options);
    /// "Press Enter when …": true on Enter alone; false on a confirmed abort or the end of input. Text
    /// other than abort/help is not taken for Enter.
    bool enter(std::string_view prompt, std::string_view what_enter_means);
    /// True when the last question ended on a confirmed abort.
    bool aborted() const { return aborted_; }

  private:
    std::optional<std::string> read_line();
    bool confirm_abort();
    void question(std::string_view prompt);

    std::istream& in_;
    std::ostream& out_;
    bool discard_;
    bool bold_;
    std::function<void()> abort_;
    bool aborted_ = false;
};

/// What an answer means among `options` (lower case, spaces and underscores read as '-'): the option's
/// index when it is one of them or the start of exactly one; the candidates when it starts several.
struct Interpretation {
    enum class Kind { option, abort, help, empty, ambiguous, unknown } kind = Kind::unknown;
    std::size_t index = 0;
    std::vector<std::size_t> candidates;
};
Interpretation interpret(std::string_view answer, const std::vector<std::string>& options);

/// "retry, accept or abort".
std::string list_options(const std::vector<std::string>& options);

}  // namespace ballbar::app
