// SPDX-License-Identifier: MIT
#include "files.hpp"

#include <cstdio>

namespace ballbar::app {

std::string readable_message(std::string_view message) {
    std::string out;
    std::size_t i = 0;
    while (i < message.size()) {
        std::size_t j = i;
        while (j < message.size() && message[j] != ' ' && message[j] != '\n' && message[j] != '\t') ++j;
        const std::string_view token = message.substr(i, j - i);
        out += token.size() > 120 ? fileio::cut(token, 40) : std::string(token);
        if (j < message.size()) out += message[j++];
        i = j;
    }
    return out.size() > 2000 ? fileio::cut(out, 2000) : out;
}

std::string printable(std::string_view text, bool keep_newlines) {
    std::string out;
    out.reserve(text.size());
    char esc[8];
    for (std::size_t i = 0; i < text.size(); ++i) {
        const auto c = static_cast<unsigned char>(text[i]);
        if (c == '\n' && keep_newlines) {
            out += '\n';
        } else if (c < 0x20 || c == 0x7f) {
            std::snprintf(esc, sizeof esc, "\\x%02x", c);
            out += esc;
        } else if (c == 0xc2 && i + 1 < text.size() && static_cast<unsigned char>(text[i + 1]) >= 0x80 &&
                   static_cast<unsigned char>(text[i + 1]) <= 0x9f) {
            std::snprintf(esc, sizeof esc, "\\u%04x", static_cast<unsigned char>(text[++i]));
            out += esc;
        } else {
            out += static_cast<char>(c);
        }
    }
    return out;
}

std::string read_file(const std::string& path, const char* what) {
    try {
        return fileio::read_json(path, what);
    } catch (const fileio::FileError& e) {
        throw as_error(e);
    }
}

std::string read_program_file(const std::string& path, const char* what) {
    try {
        return fileio::read_text(path, what);
    } catch (const fileio::FileError& e) {
        throw as_error(e);
    }
}

device::FaultConfig parse_faults_option(const std::string& spec) {
    std::string text = spec;
    const auto first = spec.find_first_not_of(" \t\n");
    if (first == std::string::npos || spec[first] != '{') text = read_file(spec, "faults file");
    try {
        return device::parse_emulator_config("{\"faults\": " + text + "}").faults;
    } catch (const std::invalid_argument& e) {
        throw Error(ErrorCategory::bad_input, std::string("--faults: ") + e.what());
    }
}

std::vector<fileio::Protected> database_files(const Globals& globals) {
    const std::string db = resolve_db_path(globals);
    return {{db, "database"},
            {db + "-wal", "database's write-ahead log"},
            {db + "-shm", "database's shared memory"},
            {db + "-journal", "database's journal"},
            {db + ".lock", "database's lock file"}};
}

void write_output(const std::string& path, std::string_view option, std::string_view text,
                  const std::vector<fileio::Protected>& inputs) {
    try {
        fileio::write_file(path, option, text, inputs);
    } catch (const fileio::FileError& e) {
        throw as_error(e);
    }
}

}  // namespace ballbar::app
