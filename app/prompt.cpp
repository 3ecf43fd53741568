// SPDX-License-Identifier: MIT
#include "prompt.hpp"

#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <istream>
#include <ostream>

namespace ballbar::app {

namespace {

std::string normalise(std::string_view text) {
    std::string out;
    for (char c : text) {
        const auto u = static_cast<unsigned char>(c);
        if (std::isspace(u) || c == '_') {
            if (!out.empty() && out.back() != '-') out += '-';
        } else {
            out += static_cast<char>(std::tolower(u));
        }
    }
    while (!out.empty() && out.back() == '-') out.pop_back();
    return out;
}

bool is_abort_word(const std::string& a) {
    return a == "abort" || a == "quit" || a == "q" || a == "stop" || a == "exit";
}

bool is_abort_option(const std::string& o) {
    return o == "abort" || o == "stop";
}

const char* const kAbortHelp = "abort (or quit) stops the session: what it measured stays stored and it can be resumed";

}  // namespace

Interpretation interpret(std::string_view answer, const std::vector<std::string>& options) {
    Interpretation r;
    const std::string a = normalise(answer);
    if (a.empty()) {
        r.kind = Interpretation::Kind::empty;
        return r;
    }
    for (std::size_t i = 0; i < options.size(); ++i)
        if (a == normalise(options[i])) {
            r.kind = is_abort_option(options[i]) ? Interpretation::Kind::abort : Interpretation::Kind::option;
            r.index = i;
            return r;
        }
    if (a == "help" || a == "?") {
        r.kind = Interpretation::Kind::help;
        return r;
    }
    if (is_abort_word(a)) {
        r.kind = Interpretation::Kind::abort;
        return r;
    }
    for (std::size_t i = 0; i < options.size(); ++i)
        if (normalise(options[i]).starts_with(a)) r.candidates.push_back(i);
    if (r.candidates.size() == 1) {
        r.index = r.candidates.front();
        r.kind = is_abort_option(options[r.index]) ? Interpretation::Kind::abort : Interpretation::Kind::option;
    } else {
        r.kind = r.candidates.empty() ? Interpretation::Kind::unknown : Interpretation::Kind::ambiguous;
    }
    return r;
}

std::string list_options(const std::vector<std::string>& options) {
    std::string out;
    for (std::size_t i = 0; i < options.size(); ++i) {
        if (i) out += i + 1 == options.size() ? " or " : ", ";
        out += options[i];
    }
    return out;
}

Prompter::Prompter(std::istream& in, std::ostream& out, bool discard_typed_ahead, bool bold,
                   std::function<void()> abort)
    : in_(in), out_(out), discard_(discard_typed_ahead), bold_(bold), abort_(std::move(abort)) {}

void Prompter::question(std::string_view prompt) {
    // Keys pressed while the machine ran (a `y`, an Enter) were typed for no question: they answer none.
    if (discard_) ::tcflush(STDIN_FILENO, TCIFLUSH);
    out_ << (bold_ ? "\033[1m" : "") << prompt << (bold_ ? "\033[0m" : "");
}

std::optional<std::string> Prompter::read_line() {
    out_.flush();
    std::string line;
    if (!std::getline(in_, line)) {
        out_ << "\n";
        return std::nullopt;
    }
    return line;
}

bool Prompter::confirm_abort() {
    out_ << "Abort the session? What it measured stays stored and it can be resumed. [yes/no] ";
    for (;;) {
        const auto line = read_line();
        if (!line) return true;  // no more answers: stopping is the safe side
        const auto r = interpret(*line, {"yes", "no"});
        if (r.kind == Interpretation::Kind::option) {
            if (r.index == 1) {
                out_ << "Not aborted.\n";
                return false;
            }
            aborted_ = true;
            if (abort_) abort_();
            return true;
        }
        out_ << "Please answer yes (abort the session) or no: ";
    }
}

bool Prompter::ready(std::string_view prompt) {
    aborted_ = false;
    question(std::string(prompt) + " [yes / not yet / abort] ");
    const std::vector<std::string> options = {"yes", "not-yet"};
    for (;;) {
        const auto line = read_line();
        if (!line) return false;
        const std::string a = normalise(*line);
        auto r = interpret(*line, options);
        if (a == "no" || a == "n" || a == "not") r = {Interpretation::Kind::option, 1, {}};
        switch (r.kind) {
            case Interpretation::Kind::option:
                if (r.index == 0) return true;
                out_ << "Not yet: take your time. Answer yes when ready (" << kAbortHelp << "): ";
                break;
            case Interpretation::Kind::abort:
                if (confirm_abort()) return false;
                out_ << prompt << " [yes / not yet / abort] ";
                break;
            case Interpretation::Kind::help:
                out_ << "yes: go on; not yet (or no): this question waits; " << kAbortHelp << ": ";
                break;
            default:
                out_ << "Please answer yes, not yet or abort: ";
        }
    }
}

std::optional<std::size_t> Prompter::choose(std::string_view prompt, const std::vector<std::string>& options) {
    aborted_ = false;
    const bool has_abort = std::any_of(options.begin(), options.end(), is_abort_option);
    const std::string choices = list_options(options) + (has_abort ? "" : " (or abort)");
    question(std::string(prompt) + "\nAnswer " + choices + ": ");
    for (;;) {
        const auto line = read_line();
        if (!line) return std::nullopt;
        const auto r = interpret(*line, options);
        switch (r.kind) {
            case Interpretation::Kind::option:
                return r.index;
            case Interpretation::Kind::abort:
                if (confirm_abort()) {
                    const auto it = std::find_if(options.begin(), options.end(), is_abort_option);
                    if (it == options.end()) return std::nullopt;
                    return static_cast<std::size_t>(it - options.begin());
                }
                out_ << "Answer " << choices << ": ";
                break;
            case Interpretation::Kind::ambiguous: {
                std::vector<std::string> which;
                for (std::size_t i : r.candidates) which.push_back(options[i]);
                out_ << "\"" << normalise(*line) << "\" could be " << list_options(which)
                     << ": type more of the word: ";
                break;
            }
            case Interpretation::Kind::help:
                out_ << "Type one of " << choices << " (the start of a word is enough when only one begins so); "
                     << kAbortHelp << ": ";
                break;
            default:
                out_ << "Please answer " << choices << ": ";
        }
    }
}

bool Prompter::enter(std::string_view prompt, std::string_view what_enter_means) {
    aborted_ = false;
    question(std::string(prompt) + "\nPress Enter " + std::string(what_enter_means) + " (or type abort). ");
    for (;;) {
        const auto line = read_line();
        if (!line) return false;
        const auto r = interpret(*line, {});
        switch (r.kind) {
            case Interpretation::Kind::empty:
                return true;
            case Interpretation::Kind::abort:
                if (confirm_abort()) return false;
                out_ << "Press Enter " << what_enter_means << ": ";
                break;
            case Interpretation::Kind::help:
                out_ << "Enter alone: " << what_enter_means << "; " << kAbortHelp << ": ";
                break;
            default:
                out_ << "Only Enter goes on (" << what_enter_means << "), or type abort: ";
        }
    }
}

}  // namespace ballbar::app
