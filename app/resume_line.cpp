// SPDX-License-Identifier: MIT
#include "resume_line.hpp"

#include <cctype>

namespace ballbar::app {

std::string shell_word(std::string_view text) {
    bool plain = !text.empty();
    for (char c : text)
        if (!std::isalnum(static_cast<unsigned char>(c)) &&
            std::string_view("_-./:=@%+,").find(c) == std::string_view::npos)
            plain = false;
    if (plain) return std::string(text);
    std::string out = "'";
    for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

std::string resume_command(std::string_view procedure, std::int64_t id, const std::string& db,
                           const std::string& device, const std::string& program) {
    std::string out = "ballbar";
    if (!db.empty()) out += " --db " + shell_word(db);
    out += procedure == "circular" ? " circle measure" : " measure";
    out +=
        " --resume " + std::to_string(id) + " --device " + (device.empty() ? std::string("URI") : shell_word(device));
    if (!program.empty()) out += " --program " + shell_word(program);
    return out;
}

std::string state_reason(std::string_view state, std::string_view reason) {
    for (int i = 0; i < 2; ++i) {  // the audit trail's "state: " and the reason's own "state "
        for (const char* sep : {": ", " "}) {
            const std::string prefix = std::string(state) + sep;
            if (reason.starts_with(prefix) && reason.size() > prefix.size()) {
                reason.remove_prefix(prefix.size());
                break;
            }
        }
    }
    return std::string(reason);
}

}  // namespace ballbar::app
