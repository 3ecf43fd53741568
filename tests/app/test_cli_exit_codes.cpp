// SPDX-License-Identifier: MIT
// The exit-code table of docs/cli.md, run: every subcommand's failure cases (bad option, missing
// required option, missing or malformed file, bad device URI, no such session or model, a duplicate
// import, a non-terminal standard input), each checked for its code, the one "ballbar: error:" line
// (JSON for `solve`, as its help says), and that it left nothing: no database where there was none,
// no new session where there was one, no output file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_harness.hpp"

namespace ballbar::test {
namespace {

namespace fs = std::filesystem;
const fs::path kDataExitCodes = fs::path(BALLBAR_TEST_DATA_DIR);

/// One row of the table: the command line (after `--db DIR/test.db`), the code it must exit with, a
/// piece of its message, and the files (in the scratch directory) it must not leave behind.
struct Case {
    std::string args;
    int code;
    std::string says;
    std::vector<std::string> no_files = {};
};

std::string data_exit_codes(const std::string& rel) {
    return "'" + (kDataExitCodes / rel).string() + "'";
}

/// The scratch directory's inputs: a machine file, a malformed one, an NC program.
void write_inputs(const TempDir& d) {
    std::ofstream(d.file("bad-machine.json")) << "{\"format\": \"ballbar-machine/1\", \"type\": ";
    std::ofstream(d.file("prog.nc")) << "%\nO0001\nG90 G1 X1 Y2 Z3 A0 C0 F100\nM30\n%\n";
    std::ofstream(d.file("bad-plan.json")) << "{\"format\": \"ballbar-plan/1\", \"bar_length_mm\": -5}";
}

void expect_case(const TempDir& d, const Case& c) {
    SCOPED_TRACE("ballbar " + c.args);
    const CliRun r = run(d, c.args);
    EXPECT_EQ(r.code, c.code) << r.err << r.out;
    if (c.args.rfind("solve", 0) == 0) {  // a JSON service: its errors are JSON on stderr
        const auto j = nlohmann::json::parse(r.err, nullptr, false);
        ASSERT_FALSE(j.is_discarded()) << r.err;
        EXPECT_NE(j.value("error", "").find(c.says), std::string::npos) << r.err;
    } else {
        EXPECT_EQ(r.err.rfind("ballbar: error: ", 0), 0u) << r.err;
        EXPECT_EQ(r.err.find("ballbar: error: ", 1), std::string::npos) << "said twice: " << r.err;
        EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
    }
    for (const auto& f : c.no_files) EXPECT_FALSE(fs::exists(d.path / f)) << f << " was left behind";
}

TEST(CliExitCodes, EveryRefusedCommandLineExits2AndCreatesNoDatabase) {
    TempDir d;
    write_inputs(d);
    const std::string machine = data_exit_codes("machines/tttrr.json");
    const std::string quick = data_exit_codes("machines/tttrr-quick.plan.json");
    const std::vector<Case> cases = {
        // The command line itself.
        {"mesure", 2, "did you mean 'measure'?"},
        {"demo --bogus", 2, "--bogus"},
        {"identify", 2, "required"},
        {"devices --bogus", 2, "--bogus"},
        {"completion fish", 2, "fish"},
        {"demo --machine XYZ", 2, "XYZ"},
        {"demo --plan missing.plan.json", 2, "missing.plan.json"},
        // measure: refused before any session is stored.
        {"measure --device emulator: --non-interactive", 2, "--machine FILE or --asset ID is required"},
        {"measure --device emulator: --asset M-1 --non-interactive", 2, "no database"},
        {"machines add M-1 --machine missing-machine.json", 2, "missing-machine.json"},
        {"machines add M-1 --machine " + d.file("bad-machine.json"), 2, "bad-machine.json"},
        {"machines show M-1", 2, "no database"},
        {"measure --machine " + machine + " --non-interactive", 2, "--device URI is required"},
        {"measure --device bogus:x --machine " + machine + " --non-interactive", 2, "bad device URI 'bogus:x'"},
        {"measure --device tcp:localhost --machine " + machine + " --non-interactive", 2, "missing HOST:PORT"},
        {"measure --device usb:zz:1 --machine " + machine + " --non-interactive", 2, "hex digits"},
        {"measure --device 'sylvac:/dev/ttyUSB0?sign=2' --machine " + machine + " --non-interactive", 2,
         "sign must be 1 or -1"},
        {"measure --device emulator:missing-emulator.json --machine " + machine + " --non-interactive", 2,
         "missing-emulator.json"},
        {"measure --device emulator: --machine missing-machine.json --non-interactive", 2, "missing-machine.json"},
        {"measure --device emulator: --machine " + d.file("bad-machine.json") + " --non-interactive", 2, ""},
        {"measure --device emulator: --machine " + machine + " --plan missing.plan.json --non-interactive", 2,
         "missing.plan.json"},
        {"measure --device emulator: --machine " + machine + " --plan " + d.file("bad-plan.json") +
             " --non-interactive",
         2, ""},
        {"measure --device emulator: --machine " + machine + " --plan " + quick, 2, "standard input is not a terminal"},
        {"measure --resume 99 --device emulator: --non-interactive", 2, "no database at"},
        {"measure --dry-run", 2, "--machine FILE (or --asset ID) is required"},
        // Readers: a database that does not exist is not created.
        {"sessions show 1", 2, "no database at"},
        {"report 1 --out r.pdf", 2, "no database at", {"r.pdf"}},
        {"report 1", 2, "nothing to write"},
        {"export 1 --format json --out x.json", 2, "no database at", {"x.json"}},
        {"export 1 --format bogus --out x.json", 2, "bogus", {"x.json"}},
        {"identify nonexist.readings", 2, "no such file: nonexist.readings"},
        {"identify 1", 2, "no database at"},
        {"identify --params bogus " + data_exit_codes("readings/rrttt_minimal.csv"), 2, "unknown parameter 'bogus'"},
        {"discover nonexist.readings", 2, "no such file: nonexist.readings"},
        {"discover 1", 2, "no database at"},
        // Valid readings, too few for the unknowns: the same failure, the same code, in both.
        {"identify " + data_exit_codes("readings/rrttt_minimal.csv"), 1, "more readings than unknowns"},
        {"discover " + data_exit_codes("readings/rrttt_minimal.csv"), 1, "more readings than unknowns"},
        {"compensate --model 1 --program " + d.file("prog.nc") + " --out o.nc", 2, "no database at", {"o.nc"}},
        {"compensate --model missing-model --program " + d.file("prog.nc") + " --out o.nc",
         2,
         "missing-model",
         {"o.nc"}},
        {"compensate --model 1 --program " + d.file("prog.nc"), 2, "--out", {"o.nc"}},
        // Inputs.
        {"import nonexist.readings", 2, "nonexist.readings"},
        {"import " + data_exit_codes("readings/invalid/bad_magic.csv"), 2, "nothing imported"},
        {"solve ssm --input missing-request.json", 2, "no such request file: missing-request.json"},
        // Instruments.
        {"monitor --device bogus:x --seconds 1", 2, "bad device URI"},
        {"monitor --seconds 1", 2, "--device"},
        {"emulate", 2, "--pty"},
        {"emulate --pty --config missing-emulator.json", 2, "missing-emulator.json"},
    };
    for (const Case& c : cases) {
        expect_case(d, c);
        ASSERT_FALSE(fs::exists(d.path / "test.db")) << "ballbar " << c.args << " created the database";
    }
}

TEST(CliExitCodes, NotFoundIs2EverywhereAndLeavesTheDatabaseAsItWas) {
    TempDir d;
    write_inputs(d);
    const std::string readings = data_exit_codes("readings/rrttt_minimal.csv");
    ASSERT_EQ(run(d, "import " + readings).code, 0);
    const std::string machine = data_exit_codes("machines/tttrr.json");
    const std::vector<Case> cases = {
        {"sessions show 99", 2, "no session"},
        {"report 99 --json", 2, "no session"},
        {"report 99 --out r.pdf", 2, "no session", {"r.pdf"}},
        {"export 99 --format json --out x.json", 2, "no session", {"x.json"}},
        {"identify 99", 2, "no session"},
        {"discover 99", 2, "no session"},
        {"measure --resume 99 --device emulator: --non-interactive", 2, "no session"},
        {"measure --resume 1 --device emulator: --non-interactive", 2, "no stored plan"},
        {"measure --resume 1 --device bogus:x --non-interactive", 2, "bad device URI"},
        {"compensate --model 99 --program " + d.file("prog.nc") + " --out o.nc", 2, "model 99", {"o.nc"}},
        {"compensate --model no-such-name --program " + d.file("prog.nc") + " --out o.nc", 2, "no-such-name", {"o.nc"}},
        {"import " + readings, 2, "already imported as session 1"},
        {"measure --device bogus:x --machine " + machine + " --non-interactive", 2, "bad device URI"},
    };
    for (const Case& c : cases) expect_case(d, c);
    const CliRun list = run(d, "sessions --json");
    ASSERT_EQ(list.code, 0);
    const auto sessions = nlohmann::json::parse(list.out);
    ASSERT_EQ(sessions.size(), 1u) << "no refused command stored a session: " << list.out;
    EXPECT_EQ(sessions[0].value("state", ""), "completed") << "the imported session is as it was";
}

}  // namespace
}  // namespace ballbar::test
