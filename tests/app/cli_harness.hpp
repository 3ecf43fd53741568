// SPDX-License-Identifier: MIT
// Running the built `ballbar` as a whole process in a scratch directory: what the CLI tests share.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace ballbar::test {

/// What one run of the CLI left: exit code, stdout, stderr.
struct CliRun {
    int code = -1;
    std::string out, err;
};

inline std::string slurp(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

/// A scratch directory removed at the end of the test; the runs' database is `file("test.db")`.
struct TempDir {
    std::filesystem::path path;
    TempDir() {
        char tmpl[] = "/tmp/ballbar-cli-XXXXXX";
        const char* d = ::mkdtemp(tmpl);
        if (!d) throw std::runtime_error("mkdtemp failed");
        path = d;
    }
    ~TempDir() { std::filesystem::remove_all(path); }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    std::string file(const std::string& name) const { return (path / name).string(); }
};

/// Runs `ballbar --db <dir>/test.db <args>` with `input` on stdin; captures stdout, stderr and the exit code.
inline CliRun run(const TempDir& dir, const std::string& args, const std::string& input = "") {
    std::ofstream(dir.path / "stdin") << input;
    const std::string cmd = std::string("'") + BALLBAR_EXE + "' --db '" + dir.file("test.db") + "' " + args + " <'" +
                            dir.file("stdin") + "' >'" + dir.file("stdout") + "' 2>'" + dir.file("stderr") + "'";
    const int status = std::system(cmd.c_str());
    CliRun r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(dir.path / "stdout");
    r.err = slurp(dir.path / "stderr");
    return r;
}

}  // namespace ballbar::test
