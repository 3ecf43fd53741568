// SPDX-License-Identifier: MIT
#include <unistd.h>
#if defined(__GLIBC__)
#include <malloc.h>
#include <sys/mman.h>
#endif

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <string_view>
#include <vector>

#include "ballbar/version.hpp"
#include "cli_main.hpp"
#include "command.hpp"
#include "files.hpp"

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
        throw Error(ErrorCategory::bad_input,
                    "cannot find a data directory: set XDG_DATA_HOME or HOME, or pass --db PATH");
    }
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw Error(ErrorCategory::failed, "cannot create " + dir.string() + ": " + ec.message());
    return (dir / "ballbar.db").string();
}

namespace {
bool g_database_damaged = false;  // note_database_damage was called: the command ends with kExitFailure
}  // namespace

void note_database_damage(const std::string& damage) {
    if (damage.empty()) return;
    g_database_damaged = true;
    std::cerr << "ballbar: warning: " << printable(damage, true)
              << " What this command shows of it may be incomplete; it will exit with code " << kExitFailure << ".\n";
}

std::string existing_db_path(const Globals& globals) {
    const std::string path = resolve_db_path(globals);
    std::error_code ec;
    if (!std::filesystem::exists(path, ec))
        throw Error(ErrorCategory::bad_input,
                    "no database at " + path + (globals.db_path.empty() ? "" : " (check --db)"));
    return path;
}

CLI::Validator in_range(double lo, double hi, std::string unit, bool lo_open) {
    auto text = [](double v) {
        std::ostringstream os;
        os << v;
        return os.str();
    };
    std::string range = (lo_open ? "(" : "[") + text(lo) + ", " + text(hi) + "]" + (unit.empty() ? "" : " " + unit);
    return CLI::Validator(
        [lo, hi, lo_open, range](std::string& value) -> std::string {
            const char* begin = value.c_str();
            char* end = nullptr;
            errno = 0;
            const double v = std::strtod(begin, &end);
            if (end == begin || *end != '\0') return "'" + value + "' is not a number";
            if (!std::isfinite(v) || errno == ERANGE) return value + " is not a finite number";
            if (v > hi || (lo_open ? !(v > lo) : !(v >= lo))) return value + " is outside " + range;
            return {};
        },
        range);
}

namespace {

std::size_t edit_distance(std::string_view a, std::string_view b) {
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        std::size_t diagonal = row[0];
        row[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j) {
            const std::size_t up = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
            diagonal = up;
        }
    }
    return row[b.size()];
}

/// The message for a first word that is no subcommand ("unknown command 'mesure'; did you mean
/// 'measure'?"), or nothing. Global options before it (`--db PATH`) are skipped.
std::optional<std::string> unknown_command(const CLI::App& root, int argc, char** argv) {
    for (int i = 1; i < argc; ++i) {
        const std::string_view arg = argv[i];
        if (arg == "--db") {
            ++i;
            continue;
        }
        if (arg.starts_with("-")) continue;
        std::vector<std::string> names;
        for (const CLI::App* s : root.get_subcommands([](const CLI::App* s) { return !s->get_group().empty(); }))
            names.push_back(s->get_name());
        if (std::find(names.begin(), names.end(), arg) != names.end()) return std::nullopt;
        std::string best;
        std::size_t best_d = 3;  // suggest only what is a small slip away
        for (const auto& n : names) {
            const std::size_t d = n.starts_with(arg) && arg.size() >= 2 ? 1 : edit_distance(arg, n);
            if (d < best_d) best_d = d, best = n;
        }
        std::string msg = "unknown command '" + std::string(arg) + "'";
        msg += best.empty() ? " (ballbar --help lists the commands)" : "; did you mean '" + best + "'?";
        return msg;
    }
    return std::nullopt;
}

/// "--devce" on `measure`: "did you mean --device?" — the long option of the command (or of the
/// commands above it) a small slip away from an option the command does not have; empty when none is.
std::string option_suggestion(CLI::App& root, int argc, char** argv) {
    std::vector<CLI::App*> chain = {&root};
    std::string suggestion;
    for (int i = 1; i < argc; ++i) {
        const std::string_view arg = argv[i];
        if (!arg.starts_with("--")) {
            auto subs = chain.back()->get_subcommands([arg](const CLI::App* s) { return s->get_name() == arg; });
            if (!subs.empty()) chain.push_back(subs.front());
            continue;
        }
        const std::string name(
            arg.substr(2, arg.find('=') == std::string_view::npos ? std::string_view::npos : arg.find('=') - 2));
        std::vector<std::string> known;
        for (const CLI::App* app : chain)
            for (const CLI::Option* o : app->get_options())
                for (const std::string& l : o->get_lnames()) known.push_back(l);
        if (name.empty() || std::find(known.begin(), known.end(), name) != known.end()) continue;
        std::size_t best_d = 3;  // a small slip, as for commands
        for (const auto& k : known) {
            const std::size_t d = k.starts_with(name) && name.size() >= 3 ? 1 : edit_distance(name, k);
            if (d < best_d) best_d = d, suggestion = "--" + k;
        }
        if (!suggestion.empty()) return "unknown option --" + name + "; did you mean " + suggestion + "?";
    }
    return {};
}

#if defined(__GLIBC__)
// AddressSanitizer's own allocator would poison the block (16 MiB of shadow) and quarantine it (below):
// GCC says so with __SANITIZE_ADDRESS__, clang (14) with __has_feature only.
#if defined(__SANITIZE_ADDRESS__)
#define BALLBAR_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define BALLBAR_ASAN 1
#endif
#endif

/// Grows the heap by `bytes` of address space (nothing is touched) and asks the kernel to back the
/// part aligned to 2 MiB with transparent huge pages, then frees it to the heap's top, where the next
/// large buffers are carved from. A 4 KiB page costs a fault each time a buffer first touches it, and
/// on a virtual machine a fault costs tens of µs: `circle analyze` of 10⁵ samples took 6,300 faults,
/// about half its time (bench/circular). Where the kernel has no huge pages for madvise, madvise
/// fails and nothing changes.
void reserve_heap_on_huge_pages(std::size_t bytes) {
#if defined(BALLBAR_ASAN)
    (void)bytes;
#else
    static bool done = false;  // once a process (the CLI fuzzer calls the command line again and again)
    if (done) return;
    done = true;
    constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;
    void* block = std::malloc(bytes);
    if (block == nullptr) return;
    const auto at = reinterpret_cast<std::uintptr_t>(block);
    const std::uintptr_t begin = (at + kHuge - 1) & ~(kHuge - 1), end = (at + bytes) & ~(kHuge - 1);
    if (end > begin) (void)madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
    std::free(block);
#endif
}
#endif

}  // namespace
}  // namespace ballbar::app

int ballbar::app::cli_main(int argc, char** argv) {
    using namespace ballbar::app;
#if defined(__GLIBC__)
    // An analysis asks for large buffers (10⁵ samples: a 10 MB design matrix, an FFT's buffers) and
    // frees them within one command; glibc would give each back to the kernel and fault the next one's
    // pages in again, page by page (a sixth of `circle analyze`'s time, bench/circular). Kept in the
    // heap for reuse instead: a command lives seconds, or holds little.
    mallopt(M_MMAP_THRESHOLD, 256 << 20);
    mallopt(M_TRIM_THRESHOLD, 512 << 20);
    // BALLBAR_NO_HEAP_RESERVE=1 leaves it out for a heap profiler (heaptrack), whose peak it would be.
    if (!std::getenv("BALLBAR_NO_HEAP_RESERVE")) reserve_heap_on_huge_pages(std::size_t{128} << 20);
#endif
    CLI::App root{"ballbar: guided ball-bar measurement and error analysis of five-axis machine tools", "ballbar"};
    root.set_version_flag("--version", std::string("ballbar ") + ballbar::kVersion);
    root.require_subcommand(1);
    root.fallthrough();

    Globals globals;
    globals.color = ::isatty(STDOUT_FILENO) && !std::getenv("NO_COLOR");
    root.add_option("--db", globals.db_path, "SQLite database (default $XDG_DATA_HOME/ballbar/ballbar.db)")
        ->check(CLI::Validator(
            [](std::string& path) -> std::string {
                // An empty path is a script's unset variable, not a wish for the default database.
                return path.empty() ? "an empty path; leave --db out to use the default database" : "";
            },
            "PATH"));

    auto& entries = registry();
    std::sort(entries.begin(), entries.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
    for (const auto& e : entries) e.setup(root, globals);
    add_help_footers(root);

    if (const auto unknown = unknown_command(root, argc, argv)) {
        std::cerr << "ballbar: error: " << printable(*unknown) << '\n';
        return kExitUsage;
    }
    try {
        root.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return root.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return root.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return root.exit(e);
    } catch (const CLI::ParseError& e) {
        // CLI11's own message, in the one error format, with where to look.
        std::cerr << "ballbar: error: " << printable(e.what(), true) << '\n';
        if (const std::string hint = option_suggestion(root, argc, argv); !hint.empty())
            std::cerr << "ballbar: " << printable(hint) << '\n';
        std::cerr << "Run with --help for more information.\n";
        return kExitUsage;
    }
    try {
        const int code = globals.action ? globals.action() : kExitOk;
        return code == kExitOk && g_database_damaged ? kExitFailure : code;
    } catch (const std::exception& e) {
        // Every error once, in the one format; its category decides the exit code (command.hpp). A
        // session stopped on purpose (Ctrl-C, an abort at a prompt) is no error: it is said as what it is.
        const auto category = workflow::category_of(e);
        std::cerr << (category == workflow::ErrorCategory::interrupted ? "ballbar: stopped: " : "ballbar: error: ")
                  << printable(readable_message(e.what()), true) << '\n';
        return exit_code(category);
    }
}
