// SPDX-License-Identifier: MIT
// libFuzzer target: the JSON inputs the `ballbar` commands themselves read — `solve ssm`, `solve
// orientation` and `solve compensate` requests, the model (`compensate --model FILE`) and the offsets
// table (`compensate --offsets FILE`) — through the real command line, ballbar::app::cli_main (app/'s
// objects are linked in). The first byte picks the input; the rest is the file. Properties: the command
// ends with exit 0, 1 or 2 (no crash, no uncaught exception), and a refusal names the problem in our words,
// never with a JSON library's type or range error ("[json.exception.type_error…": a value used unchecked).
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "cli_main.hpp"
#include "fuzz_check.hpp"

using ballbar::fuzz::check;

namespace {

struct Files {
    std::string dir, input, program, model, out;
    Files() {
        char tmpl[] = "/tmp/ballbar-fuzz-cli-XXXXXX";
        if (!::mkdtemp(tmpl)) std::abort();
        dir = tmpl;
        input = dir + "/input.json";
        program = dir + "/p.nc";
        model = dir + "/model.json";
        std::ofstream(program) << "%\nO1000\nG90 G1 X10 Y0 Z0 A10 C20 F1000\nX20 C40\nM30\n%\n";
        std::ofstream(model) << R"({"format":"ballbar-model/1","machine":{"type":"TTTRR","c_offset_mm":[0,0,-100]},)"
                             << R"("params":{"X0C":0.001}})";
    }
};

int run(std::vector<std::string> args) {
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    return ballbar::app::cli_main(static_cast<int>(args.size()), argv.data());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static Files files;
    if (size < 1) return 0;
    {
        std::ofstream f(files.input, std::ios::binary | std::ios::trunc);
        f.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
    }
    std::vector<std::string> args{"ballbar"};
    switch (data[0] % 5) {
        case 0:
            args.insert(args.end(), {"solve", "ssm", "--input", files.input});
            break;
        case 1:
            args.insert(args.end(), {"solve", "orientation", "--input", files.input});
            break;
        case 2:
            args.insert(args.end(), {"solve", "compensate", "--input", files.input});
            break;
        case 3:
            args.insert(args.end(), {"compensate", "--model", files.input, "--program", files.program, "--out", "-"});
            break;
        case 4:
            args.insert(args.end(), {"compensate", "--model", files.model, "--program", files.program, "--offsets",
                                     files.input, "--out", "-"});
            break;
    }
    std::ostringstream out, err;
    auto* cout_buf = std::cout.rdbuf(out.rdbuf());
    auto* cerr_buf = std::cerr.rdbuf(err.rdbuf());
    const int code = run(args);
    std::cout.rdbuf(cout_buf);
    std::cerr.rdbuf(cerr_buf);
    // "malformed JSON: [json.exception.parse_error…] … at line 1, column 49" names the problem (and where);
    // a type_error or out_of_range from the library means a value was used without being checked.
    // (Only before a parse error's "last read: '…'", which quotes the input, whatever it holds.)
    // A refusal may quote the input (an unknown field's name), so the library's words count only when
    // the input does not hold them itself (found by a longer run: a field named
    // "json.exception.out_of_rangecket_mm", rightly refused as an unknown field, naming it).
    const std::string e = err.str().substr(0, err.str().find("last read:"));
    const bool quoted =
        std::string_view(reinterpret_cast<const char*>(data), size).find("json.exception") != std::string_view::npos;
    const bool raw = !quoted && (e.find("json.exception.type_error") != std::string::npos ||
                                 e.find("json.exception.out_of_range") != std::string::npos ||
                                 e.find("json.exception.invalid_iterator") != std::string::npos ||
                                 e.find("json.exception.other_error") != std::string::npos);
    if (!(code == 0 || code == 1 || code == 2) || raw) {
        std::fprintf(stderr, "exit %d, stderr: %s\n", code, err.str().c_str());
        check(false, "exit 0, 1 or 2 with a message in our words");
    }
    return 0;
}
