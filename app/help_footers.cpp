// SPDX-License-Identifier: MIT
// The end of every subcommand's --help: examples and the exit codes. One table here, applied to the
// registered commands after they are set up, so that every command's help has the same shape and a
// command without examples is caught by a test (tests/app/test_cli_help.cpp).
#include <map>
#include <string>

#include "command.hpp"

namespace ballbar::app {
namespace {

const std::map<std::string, std::string>& examples() {
    static const std::map<std::string, std::string> table{
        {"circle",
         "  ballbar circle plan --plane XY --radius 100 --feed 1000 --out circle.nc\n"
         "  ballbar circle analyze trace.csv --json --tolerance 15\n"
         "  ballbar circle measure --device serial:/dev/ttyACM0 --test test.json   # guided, stored\n"
         "  ballbar circle analyze 4 --controller linuxcnc     # the measured backlash as INI settings\n"},
        {"compensate",
         "  ballbar compensate --model tttrr --program part.nc --out part-comp.nc\n"
         "  ballbar compensate --model model.json --program part.ngc --out - --exact > comp.ngc\n"
         "  ballbar compensate --model 3 --program part.nc --out - --json > comp.nc 2> report.json\n"},
        {"completion", "  ballbar completion bash > ~/.local/share/bash-completion/completions/ballbar\n"},
        {"demo",
         "  ballbar demo                                 # TTTRR, the guided procedure on the emulator\n"
         "  ballbar demo --machine RRTTT --json\n"
         "  ballbar demo --report demo.pdf --compensate\n"
         "  ballbar demo --instrument digimatic           # the procedure on an emulated digital gauge\n"
         "  ballbar demo --test circular --plane ZX       # the circular test, each diagnostic against the truth\n"},
        {"devices", "  ballbar devices\n  ballbar devices --json\n"},
        {"discover", "  ballbar discover readings.csv --json\n  ballbar discover 3\n"},
        {"emulate",
         "  ballbar emulate --pty                        # prints the pty path to pass to measure\n"
         "  ballbar emulate --instrument sylvac --pty     # a Sylvac indicator instead\n"},
        {"export",
         "  ballbar export 3 --format readings --out s3.csv\n"
         "  ballbar export 3 --format json --out s3.json\n"},
        {"identify", "  ballbar identify 3 4 --json\n  ballbar identify readings.csv --params all --name mill-1\n"},
        {"import",
         "  ballbar import s3.csv\n"
         "  ballbar import s3.csv --allow-duplicate       # content imported before: refused without it\n"},
        {"measure",
         "  ballbar measure --device serial:/dev/ttyACM0 --machine machine.json\n"
         "  ballbar measure --device serial:/dev/pts/5 --machine machine.json --plan plan.json\n"
         "  ballbar measure --resume 7 --device serial:/dev/ttyACM0\n"
         "  ballbar measure --non-interactive --device serial:/dev/ttyACM0 --machine m.json --plan ci.json  # CI\n"},
        {"monitor",
         "  ballbar monitor --device serial:/dev/ttyACM0 --seconds 2 --json\n"
         "  ballbar monitor --device sylvac:/dev/ttyUSB0\n"},
        {"machines",
         "  ballbar machines add M-0042 --machine mill.json --location \"hall 2\" --circularity-tolerance 12\n"
         "  ballbar machines                             # the registry\n"
         "  ballbar machines show M-0042 --json\n"
         "  ballbar measure --asset M-0042 --device serial:/dev/ttyUSB0   # measured, listed, trended under it\n"},
        {"report", "  ballbar report 3 --out s3.pdf\n  ballbar report 3 --json\n"},
        {"serve",
         "  ballbar serve                                # http://127.0.0.1:8230/ on this machine only\n"
         "  ballbar serve --demo                          # the circular demo waits for the first screen\n"
         "  ballbar serve --host 0.0.0.0 --token-file /etc/ballbar/token   # the shop's network, with a token\n"},
        {"sessions",
         "  ballbar sessions\n  ballbar sessions show 3 --json\n  ballbar sessions trend \"TTTRR mill-1\" --json   # "
         "headline figures over months\n"},
        {"sync",
         "  ballbar sync \"host=db.plant dbname=ballbar user=station7\"    # results, points, models; PGPASSWORD\n"
         "  ballbar sync \"postgresql://station7@db.plant/ballbar\" --samples --json   # and the raw samples\n"
         "  (exit 1 also when ids of this station are on the server under another: conflicts, not merged)\n"},
        {"trend",
         "  ballbar trend M-0042                          # this station's sessions of the machine\n"
         "  ballbar trend M-0042 --from \"host=db.plant dbname=ballbar user=quality\" --since 2026-01-01 --out "
         "m42.pdf\n"
         "  ballbar trend M-0042 --json\n"},
        {"udev-rules", "  ballbar udev-rules > 70-ballbar-gauges.rules\n  ballbar udev-rules --plugdev\n"},
        {"solve", "  ballbar solve ssm < request.json\n  ballbar solve orientation --input request.json\n"},
    };
    return table;
}

constexpr const char* kExitCodes =
    "Exit codes:\n"
    "  0  success\n"
    "  1  the operation failed (instrument lost, database error, measurement aborted by its checks)\n"
    "  2  bad command line or malformed input (the message names the option, field or line); no such\n"
    "     session or model; nothing is stored\n"
    "  3  interrupted (Ctrl-C); what was measured is stored and can be resumed";

}  // namespace

void add_help_footers(CLI::App& root) {
    for (CLI::App* sub : root.get_subcommands([](CLI::App* s) { return !s->get_group().empty(); })) {
        std::string footer = sub->get_footer();
        if (footer.find("Examples:") == std::string::npos) {
            const auto it = examples().find(sub->get_name());
            if (it != examples().end()) footer = "Examples:\n" + it->second + (footer.empty() ? "" : "\n" + footer);
        }
        if (!footer.empty()) footer += footer.back() == '\n' ? "\n" : "\n\n";
        sub->footer(footer + kExitCodes);
    }
    root.footer(std::string("Run `ballbar COMMAND --help` for a command's options and examples.\n") + kExitCodes);
}

}  // namespace ballbar::app
