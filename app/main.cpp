// SPDX-License-Identifier: MIT
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <vector>

#include "ballbar/version.hpp"
#include "command.hpp"

namespace ballbar::app {
namespace {

struct Entry {
    std::string_view name;
    CommandSetup setup;
};

std::vector<Entry>& registry() {
    static std::vector<Entry> entries;
    return entries;
}

}  // namespace

CommandRegistrar::CommandRegistrar(std::string_view name, CommandSetup setup) {
    registry().push_back({name, setup});
}

std::string resolve_db_path(const Globals& globals) {
    if (!globals.db_path.empty()) return globals.db_path;
    std::filesystem::path dir;
    if (const char* xdg = std::getenv("XDG_DATA_HOME"); xdg && *xdg) {
        dir = std::filesystem::path(xdg) / "ballbar";
    } else if (const char* home = std::getenv("HOME"); home && *home) {
        dir = std::filesystem::path(home) / ".local" / "share" / "ballbar";
    } else {
        throw CliError(kExitUsage, "cannot find a data directory: set XDG_DATA_HOME or HOME, or pass --db PATH");
    }
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw CliError(kExitFailure, "cannot create " + dir.string() + ": " + ec.message());
    return (dir / "ballbar.db").string();
}

std::string read_file(const std::string& path, const char* what) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw CliError(kExitUsage, std::string("cannot read the ") + what + " " + path);
    std::ostringstream text;  // a million-block NC program is ~50 MB
    text << in.rdbuf();
    if (in.bad()) throw CliError(kExitUsage, std::string("read failed: ") + what + " " + path);
    return std::move(text).str();
}

}  // namespace ballbar::app

int main(int argc, char** argv) {
    using namespace ballbar::app;
    CLI::App root{"ballbar: guided ball-bar measurement and error analysis of five-axis machine tools", "ballbar"};
    root.set_version_flag("--version", std::string("ballbar ") + ballbar::kVersion);
    root.require_subcommand(1);
    root.fallthrough();

    Globals globals;
    globals.color = ::isatty(STDOUT_FILENO) && !std::getenv("NO_COLOR");
    root.add_option("--db", globals.db_path, "SQLite database (default $XDG_DATA_HOME/ballbar/ballbar.db)");

    auto& entries = registry();
    std::sort(entries.begin(), entries.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
    for (const auto& e : entries) e.setup(root, globals);

    try {
        root.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return root.exit(e) == 0 ? kExitOk : kExitUsage;
    }
    try {
        return globals.action ? globals.action() : kExitOk;
    } catch (const CliError& e) {
        std::cerr << "ballbar: " << e.what() << '\n';
        return e.code();
    } catch (const std::exception& e) {
        std::cerr << "ballbar: error: " << e.what() << '\n';
        return kExitFailure;
    }
}
