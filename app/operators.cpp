// SPDX-License-Identifier: MIT
#include "operators.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "ballbar/fileio/output.hpp"
#include "interrupt.hpp"

namespace ballbar::app {

namespace acq = ballbar::acquisition;
using nlohmann::json;

namespace {

std::string where(const acq::PlannedPoint& p) {
    return "test " + std::to_string(p.test + 1) + " step " + std::to_string(p.step) + " point " +
           std::to_string(p.point + 1);
}

std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

std::string trim(const std::string& s) {
    const auto a = s.find_first_not_of(" \t\r\n");
    if (a == std::string::npos) return {};
    return s.substr(a, s.find_last_not_of(" \t\r\n") - a + 1);
}

/// "[r]etry, [a]ccept or a[b]ort": each option with its letter (the first letter no earlier option has).
std::vector<char> letters(const std::vector<std::string>& options) {
    std::vector<char> out;
    for (const std::string& o : options) {
        char pick = 0;
        for (char c : o)
            if (std::isalpha(static_cast<unsigned char>(c)) && std::find(out.begin(), out.end(), c) == out.end()) {
                pick = c;
                break;
            }
        out.push_back(pick);
    }
    return out;
}

std::string options_text(const std::vector<std::string>& options) {
    const auto keys = letters(options);
    std::string out;
    for (std::size_t i = 0; i < options.size(); ++i) {
        if (i) out += i + 1 == options.size() ? " or " : ", ";
        const std::string& o = options[i];
        const auto at = o.find(keys[i]);
        out += at == std::string::npos ? o : o.substr(0, at) + "[" + keys[i] + "]" + o.substr(at + 1);
    }
    return out;
}

std::string duration(double s) {
    const auto total = static_cast<long>(std::lround(std::max(0.0, s)));
    std::ostringstream os;
    if (total >= 60) os << total / 60 << " min ";
    os << total % 60 << " s";
    return os.str();
}

/// The safe answer when no answer can be read: stop (resumable), else abort, else the default.
std::size_t safe_option(const acq::Choice& c) {
    for (const char* s : {"stop", "abort"})
        for (std::size_t i = 0; i < c.options.size(); ++i)
            if (c.options[i] == s) return i;
    return c.default_option;
}

acq::PointFailureAction failure_action(std::size_t i) {
    return i == 0   ? acq::PointFailureAction::Retry
           : i == 1 ? acq::PointFailureAction::Accept
                    : acq::PointFailureAction::Abort;
}

const std::vector<std::string> kFailureOptions = {"retry", "accept", "abort"};

}  // namespace

bool reads_terminal(const std::istream& in) {
    return &in == &std::cin && ::isatty(STDIN_FILENO) == 1;
}

std::optional<std::size_t> read_choice(std::istream& in, std::ostream& out, const std::vector<std::string>& options) {
    const auto keys = letters(options);
    std::string line;
    while (std::getline(in, line)) {
        const std::string a = lower(trim(line));
        for (std::size_t i = 0; i < options.size(); ++i)
            if (a == options[i] || (a.size() == 1 && a[0] == keys[i])) return i;
        out << "Please answer " << options_text(options) << ": " << std::flush;
    }
    return std::nullopt;
}

void write_program_file(const std::string& path, const analysis::NcProgram& program) {
    try {  // cmd_measure has refused a --program that is one of its inputs
        fileio::write_file(path, "--program", analysis::write_nc_program(program, "ballbar SSM"));
    } catch (const fileio::FileError& e) {
        throw acq::SourceError(std::string("cannot write the NC program: ") + e.what());
    }
}

// ---- TerminalOperator ------------------------------------------------------------------------------

TerminalOperator::TerminalOperator(std::istream& in, std::ostream& out, bool tty, const acq::Plan& plan,
                                   std::string program_path)
    : in_(in),
      prompt_(in, out, reads_terminal(in), tty, InterruptGuard::request),
      out_(out),
      tty_(tty),
      plan_(plan),
      program_path_(std::move(program_path)) {}

void TerminalOperator::end_progress_line() {
    if (progress_line_) out_ << (tty_ ? "\r\033[K" : "\n");
    progress_line_ = false;
}

bool TerminalOperator::confirm(std::string_view what, std::string_view prompt) {
    end_progress_line();
    if (what == "setup" || what == "reference") return prompt_.ready(prompt);  // "no" is "not yet"
    const auto a = prompt_.choose(prompt, {"yes", "no"});
    return a && *a == 0;
}

std::size_t TerminalOperator::choose(const acq::Choice& c) {
    end_progress_line();
    const auto a = prompt_.choose(c.prompt, c.options);
    return a ? *a : safe_option(c);
}

void TerminalOperator::message(std::string_view text) {
    end_progress_line();
    out_ << (tty_ ? "\033[36m" : "") << text << (tty_ ? "\033[0m" : "") << '\n' << std::flush;
}

acq::PointFailureAction TerminalOperator::point_failed(const acq::CapturedPoint& p, std::string_view why) {
    end_progress_line();
    const auto a =
        prompt_.choose("Point " + where(p.planned) + " failed on every attempt: " + std::string(why), kFailureOptions);
    return a ? failure_action(*a) : acq::PointFailureAction::Abort;
}

void TerminalOperator::wait_at_point(const acq::PlannedPoint& p) {
    end_progress_line();
    std::ostringstream os;
    os << "Move to " << where(p) << " (X " << p.pose.X_mm << " Y " << p.pose.Y_mm << " Z " << p.pose.Z_mm << ").";
    prompt_.enter(os.str(), "when the machine stands there");
}

void TerminalOperator::progress(const acq::Progress& p) {
    if (!tty_) return;  // a log gets the point lines, not a rewritten progress line
    constexpr int kWidth = 24;
    const double frac = p.total ? static_cast<double>(p.done) / static_cast<double>(p.total) : 0;
    const int filled = static_cast<int>(frac * kWidth);
    std::ostringstream os;
    os << "[" << std::string(static_cast<std::size_t>(filled), '#')
       << std::string(static_cast<std::size_t>(kWidth - filled), '.') << "] " << p.done << "/" << p.total << "  next "
       << "test " << p.test + 1 << " step " << p.step << " point " << p.point + 1 << "  bar ";
    os.setf(std::ios::fixed);
    if (p.out_of_range) {
        os << "\033[33mout of range";
        if (p.range_mm > 0) os << " (beyond ±" << std::setprecision(0) << p.range_mm * 1e3 << " µm)";
        os << "\033[0m";
    } else {
        const double dev_um = (p.live_mm - p.expected_mm) * 1e3;
        os.precision(4);
        os << (std::abs(dev_um) < 500 ? "\033[32m" : "\033[33m") << p.live_mm << " mm\033[0m";
        os.precision(1);
        os << " (" << (dev_um >= 0 ? "+" : "") << dev_um << " µm)";
    }
    if (p.fill > 0) os << "  averaging " << static_cast<int>(p.fill * 100) << " %";
    if (p.time_left_s > 0) os << "  ~" << duration(p.time_left_s) << " left";
    // The countdowns to the timeouts: the machine standing after the (cycle) start, the point due now.
    if (p.start_wait_left_s)
        os << "  waiting for the machine to move (timing starts in " << duration(*p.start_wait_left_s) << ")";
    else if (p.point_due_s && p.fill == 0)
        os << "  point due within " << duration(*p.point_due_s);
    out_ << "\r" << os.str() << "\033[K" << std::flush;
    progress_line_ = true;
}

void TerminalOperator::instrument_waiting(double seconds_left) {
    if (!tty_) return;  // a log has the periodic "Still no answer" lines
    out_ << "\r\033[33minstrument lost\033[0m: " << duration(seconds_left)
         << " left before the session stops (resumable); reconnect the instrument, or Ctrl-C to stop now\033[K"
         << std::flush;
    progress_line_ = true;
}

void TerminalOperator::instrument_back() {
    end_progress_line();
}

void TerminalOperator::point_captured(const acq::CapturedPoint& p) {
    end_progress_line();
    std::ostringstream os;
    os.setf(std::ios::fixed);
    os.precision(4);
    os << "  " << (tty_ ? "\033[32m✓\033[0m" : "ok") << " " << where(p.planned) << ": " << p.measured_mm << " mm";
    os.precision(2);
    os << ", σ " << p.std_mm * 1e3 << " µm (" << p.n << " samples)";
    if (p.operator_accepted) os << "  kept by the operator";
    out_ << os.str() << "\n" << std::flush;
}

void TerminalOperator::run_program(const analysis::NcProgram& program, std::span<const std::size_t> points,
                                   bool retry) {
    end_progress_line();
    if (!program_path_.empty()) {
        write_program_file(program_path_, program);
        out_ << (retry ? "Retry program" : "NC program") << " (" << points.size() << " point"
             << (points.size() == 1 ? "" : "s") << ") written to " << program_path_ << ". ";
    }
    out_ << "Load it and start it on the machine now (cycle start); it stops first for the bar." << std::endl;
}

void TerminalOperator::program_stop(const acq::ProgramStop& stop) {
    end_progress_line();
    prompt_.enter("Program stop (M0): " + stop.what + ".", "when you have pressed cycle start");
}

// ---- ScriptedTerminalOperator ----------------------------------------------------------------------

namespace {
std::istringstream& empty_input() {
    static std::istringstream empty;
    return empty;
}
}  // namespace

ScriptedTerminalOperator::ScriptedTerminalOperator(std::ostream& out, const acq::Plan& plan, std::string program)
    : TerminalOperator(empty_input(), out, false, plan, std::move(program)), answers_(plan.spec.answers) {}

bool ScriptedTerminalOperator::confirm(std::string_view what, std::string_view prompt) {
    const bool yes = answers_.confirm(what, prompt);
    out_ << prompt << " [plan: " << (yes ? "yes" : "no") << "]\n";
    return yes;
}

std::size_t ScriptedTerminalOperator::choose(const acq::Choice& c) {
    const std::size_t i = answers_.choose(c);
    out_ << c.prompt << " [plan: " << c.options[i] << "]\n";
    return i;
}

acq::PointFailureAction ScriptedTerminalOperator::point_failed(const acq::CapturedPoint& p, std::string_view why) {
    const acq::PointFailureAction a = answers_.point_failed(p, why);
    out_ << "point " << where(p.planned) << " failed: " << why
         << " [plan: " << kFailureOptions[static_cast<std::size_t>(a)] << "]\n";
    return a;
}

void ScriptedTerminalOperator::progress(const acq::Progress& p) {
    if (p.done == last_) return;
    last_ = p.done;
    out_ << "captured " << p.done << "/" << p.total << "\n" << std::flush;
}

void ScriptedTerminalOperator::program_stop(const acq::ProgramStop& stop) {
    out_ << "Program stop (M0): " << stop.what << " [plan: cycle start]\n" << std::flush;
}

// ---- JsonOperator ----------------------------------------------------------------------------------

JsonOperator::JsonOperator(std::istream& in, std::ostream& out, bool scripted, const acq::Plan& plan,
                           std::string program_path)
    : in_(in),
      out_(out),
      scripted_(scripted),
      plan_(plan),
      program_path_(std::move(program_path)),
      answers_(plan.spec.answers) {}

namespace {
void emit(std::ostream& out, const json& j) {
    out << j.dump() << "\n" << std::flush;
}
json point_json(const acq::PlannedPoint& p) {
    return {{"test", p.test + 1}, {"step", p.step}, {"point", p.point + 1}};
}
}  // namespace

bool JsonOperator::confirm(std::string_view what, std::string_view prompt) {
    json j = {{"event", "question"}, {"what", what}, {"prompt", prompt}, {"options", {"yes", "no"}}};
    bool yes = false;
    if (scripted_) {
        yes = answers_.confirm(what, prompt);
    } else {
        emit(out_, j);
        const auto a = read_choice(in_, out_, {"yes", "no"});
        yes = a && *a == 0;
    }
    j["event"] = "answer";
    j["answer"] = yes ? "yes" : "no";
    emit(out_, j);
    return yes;
}

std::size_t JsonOperator::choose(const acq::Choice& c) {
    json j = {{"event", "question"}, {"what", c.what}, {"prompt", c.prompt}, {"options", c.options}};
    std::size_t i = 0;
    if (scripted_) {
        i = answers_.choose(c);
    } else {
        emit(out_, j);
        const auto a = read_choice(in_, out_, c.options);
        i = a ? *a : safe_option(c);
    }
    j["event"] = "answer";
    j["answer"] = c.options[i];
    emit(out_, j);
    return i;
}

void JsonOperator::message(std::string_view text) {
    emit(out_, {{"event", "message"}, {"text", text}});
}

acq::PointFailureAction JsonOperator::point_failed(const acq::CapturedPoint& p, std::string_view why) {
    acq::Choice c{"point-failed", where(p.planned) + " failed on every attempt: " + std::string(why), kFailureOptions,
                  0};
    if (scripted_) {
        const auto a = answers_.point_failed(p, why);
        emit(out_, {{"event", "answer"},
                    {"what", c.what},
                    {"prompt", c.prompt},
                    {"answer", kFailureOptions[static_cast<std::size_t>(a)]}});
        return a;
    }
    return failure_action(choose(c));
}

void JsonOperator::wait_at_point(const acq::PlannedPoint& p) {
    emit(out_, {{"event", "wait_at_point"}, {"point", point_json(p)}});
    if (!scripted_) {
        std::string line;
        std::getline(in_, line);
    }
}

void JsonOperator::progress(const acq::Progress& p) {
    if (p.done == last_done_) return;  // one line per captured point, not per sample batch
    last_done_ = p.done;
    emit(out_, {{"event", "progress"},
                {"done", p.done},
                {"total", p.total},
                {"time_left_s", std::round(p.time_left_s)},
                {"live_mm", p.out_of_range ? json(nullptr) : json(p.live_mm)},
                {"out_of_range", p.out_of_range}});
}

void JsonOperator::run_program(const analysis::NcProgram& program, std::span<const std::size_t> points, bool retry) {
    if (!program_path_.empty()) write_program_file(program_path_, program);
    json pts = json::array();
    for (std::size_t i : points) pts.push_back(point_json(plan_.points[i]));
    emit(out_, {{"event", "run_program"}, {"retry", retry}, {"program", program_path_}, {"points", pts}});
}

void JsonOperator::program_stop(const acq::ProgramStop& stop) {
    emit(out_, {{"event", "program_stop"}, {"what", stop.what}});
    if (!scripted_) {
        std::string line;
        std::getline(in_, line);
    }
}

void JsonOperator::point_captured(const acq::CapturedPoint& p) {
    emit(out_, {{"event", "point"},
                {"point", point_json(p.planned)},
                {"measured_mm", p.measured_mm},
                {"sd_um", p.std_mm * 1e3},  // the readings' spread, not an uncertainty (docs/cli.md)
                {"n", p.n},
                {"operator_accepted", p.operator_accepted},
                {"evidence", p.evidence}});
}

}  // namespace ballbar::app
