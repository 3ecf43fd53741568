// SPDX-License-Identifier: MIT
// Test support: the recorded gauge byte streams of tests/data/gauges/ (format in its README.md).
#pragma once

#include <cstdint>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace ballbar::device::gauge::testing {

struct Exchange {
    std::string host;    ///< what the host must send
    std::string device;  ///< what the device answers (may be empty: no reply)
};

struct Step {
    std::string action;  ///< "identify" or "read"
    std::vector<std::string> expect;
    std::vector<Exchange> exchanges;
    int line = 0;
};

inline std::string parse_bytes(const std::string& s, int line) {
    std::string out;
    std::size_t i = s.find_first_not_of(' ');
    if (i == std::string::npos) return out;
    if (s[i] == '"') {
        for (++i; i < s.size() && s[i] != '"'; ++i) {
            if (s[i] != '\\') {
                out.push_back(s[i]);
                continue;
            }
            const char e = s[++i];
            if (e == 'r') {
                out.push_back('\r');
            } else if (e == 'n') {
                out.push_back('\n');
            } else if (e == 'x') {
                out.push_back(static_cast<char>(std::stoi(s.substr(i + 1, 2), nullptr, 16)));
                i += 2;
            } else {
                out.push_back(e);
            }
        }
        if (i >= s.size()) throw std::runtime_error("line " + std::to_string(line) + ": unterminated string");
        return out;
    }
    std::istringstream hex(s);
    std::string b;
    while (hex >> b) out.push_back(static_cast<char>(std::stoi(b, nullptr, 16)));
    return out;
}

inline std::vector<Step> load_stream(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw std::runtime_error("cannot read " + path);
    std::vector<Step> steps;
    std::string text;
    int n = 0;
    while (std::getline(in, text)) {
        ++n;
        if (text.empty() || text[0] == '#') continue;
        if (text[0] == '>' || text[0] == '<') {
            if (steps.empty()) throw std::runtime_error(path + ":" + std::to_string(n) + ": bytes before a step");
            auto& ex = steps.back().exchanges;
            if (text[0] == '>') {
                ex.push_back({parse_bytes(text.substr(1), n), {}});
            } else {
                if (ex.empty()) throw std::runtime_error(path + ":" + std::to_string(n) + ": a reply to nothing");
                ex.back().device += parse_bytes(text.substr(1), n);
            }
            continue;
        }
        std::istringstream words(text);
        Step s;
        s.line = n;
        words >> s.action;
        std::string w;
        while (words >> w) s.expect.push_back(w);
        steps.push_back(s);
    }
    return steps;
}

}  // namespace ballbar::device::gauge::testing
