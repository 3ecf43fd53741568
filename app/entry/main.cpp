// SPDX-License-Identifier: MIT
// The `ballbar` executable. Everything else of app/ is the `ballbar_cli` object library, which the
// CLI fuzzer links as well (fuzz/CMakeLists.txt).
#include "cli_main.hpp"

int main(int argc, char** argv) {
    return ballbar::app::cli_main(argc, argv);
}
