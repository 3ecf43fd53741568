// SPDX-License-Identifier: MIT
// The operator of a guided procedure, as the app offers it: at a terminal (prompts, a live progress
// line), answering from the plan file (--non-interactive, logs), or as JSON lines for CI (--json).
// The procedures talk to acquisition::Operator only; these are its implementations.
#pragma once

#include <iosfwd>
#include <string>

#include "ballbar/acquisition/interfaces.hpp"
#include "prompt.hpp"

namespace ballbar::app {

/// Reads one answer among `options` from `in`: the full word or its first letter (case-insensitive);
/// anything else is asked again. Returns nullopt at the end of the input.
std::optional<std::size_t> read_choice(std::istream& in, std::ostream& out, const std::vector<std::string>& options);

/// True when `in` is this process's standard input and that is a terminal (its typed-ahead keys can be
/// discarded before a question).
bool reads_terminal(const std::istream& in);

/// The operator at a terminal: prompts on `out`, answers from `in`; a progress line with the live bar
/// reading and the program's time left; colour and line rewriting only when `tty`. `run_program`
/// writes the program to `program_path` and asks the operator to start it.
class TerminalOperator : public acquisition::Operator {
  public:
    TerminalOperator(std::istream& in, std::ostream& out, bool tty, const acquisition::Plan& plan,
                     std::string program_path);
    bool confirm(std::string_view what, std::string_view prompt) override;
    std::size_t choose(const acquisition::Choice& choice) override;
    void message(std::string_view text) override;
    acquisition::PointFailureAction point_failed(const acquisition::CapturedPoint& p, std::string_view why) override;
    void wait_at_point(const acquisition::PlannedPoint& p) override;
    void progress(const acquisition::Progress& p) override;
    void run_program(const analysis::NcProgram& program, std::span<const std::size_t> points, bool retry) override;
    void program_stop(const acquisition::ProgramStop& stop) override;
    void point_captured(const acquisition::CapturedPoint& p) override;
    void instrument_waiting(double seconds_left) override;
    void instrument_back() override;

  protected:
    void end_progress_line();
    std::istream& in_;
    Prompter prompt_;
    std::ostream& out_;
    bool tty_;
    const acquisition::Plan& plan_;
    std::string program_path_;
    bool progress_line_ = false;
    std::size_t last_width_ = 0;
};

/// The plan file's answers, with every prompt and progress step written to `out` line by line.
class ScriptedTerminalOperator : public TerminalOperator {
  public:
    ScriptedTerminalOperator(std::ostream& out, const acquisition::Plan& plan, std::string program);
    bool confirm(std::string_view what, std::string_view prompt) override;
    std::size_t choose(const acquisition::Choice& choice) override;
    acquisition::PointFailureAction point_failed(const acquisition::CapturedPoint& p, std::string_view why) override;
    void wait_at_point(const acquisition::PlannedPoint&) override {}
    void progress(const acquisition::Progress& p) override;
    void program_stop(const acquisition::ProgramStop& stop) override;

  private:
    acquisition::ScriptedOperator answers_;
    std::size_t last_ = static_cast<std::size_t>(-1);
};

/// The same events as JSON lines on `out` (one object a line, "event" names it); answers from `in`
/// as for the terminal, or from the plan file when `scripted`.
class JsonOperator : public acquisition::Operator {
  public:
    JsonOperator(std::istream& in, std::ostream& out, bool scripted, const acquisition::Plan& plan,
                 std::string program_path);
    bool confirm(std::string_view what, std::string_view prompt) override;
    std::size_t choose(const acquisition::Choice& choice) override;
    void message(std::string_view text) override;
    acquisition::PointFailureAction point_failed(const acquisition::CapturedPoint& p, std::string_view why) override;
    void wait_at_point(const acquisition::PlannedPoint& p) override;
    void progress(const acquisition::Progress& p) override;
    void run_program(const analysis::NcProgram& program, std::span<const std::size_t> points, bool retry) override;
    void program_stop(const acquisition::ProgramStop& stop) override;
    void point_captured(const acquisition::CapturedPoint& p) override;

  private:
    std::istream& in_;
    std::ostream& out_;
    bool scripted_;
    const acquisition::Plan& plan_;
    std::string program_path_;
    acquisition::ScriptedOperator answers_;
    std::size_t last_done_ = static_cast<std::size_t>(-1);
};

/// Writes `program` to `path` (throws SourceError when it cannot).
void write_program_file(const std::string& path, const analysis::NcProgram& program);

}  // namespace ballbar::app
