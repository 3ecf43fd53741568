// SPDX-License-Identifier: MIT
// The `ballbar` command line as a function, so that the executable's main() (app/entry/main.cpp) and
// the CLI fuzzer (fuzz/fuzz_cli_json.cpp) run the same code. Deliberately free of CLI11: including it
// costs a file 6-20 s of compiling.
#pragma once

namespace ballbar::app {

/// Parses argv, runs the subcommand and returns the exit code (docs/cli.md). Prints to stdout and
/// stderr; never calls exit(). Defined in app/cli_main.cpp.
int cli_main(int argc, char** argv);

}  // namespace ballbar::app
