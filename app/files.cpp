// SPDX-License-Identifier: MIT
#include "files.hpp"

namespace ballbar::app {

CliError cli_error(const fileio::FileError& e) {
    return CliError(e.kind() == fileio::FileError::Kind::refused ? kExitUsage : kExitFailure, e.what());
}

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

std::string read_file(const std::string& path, const char* what) {
    try {
        return fileio::read_whole(path, what, fileio::kMaxJsonBytes);
    } catch (const fileio::FileError& e) {
        throw cli_error(e);
    }
}

std::string read_program_file(const std::string& path, const char* what) {
    try {
        return fileio::read_text(path, what);
    } catch (const fileio::FileError& e) {
        throw cli_error(e);
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
        throw cli_error(e);
    }
}

}  // namespace ballbar::app
