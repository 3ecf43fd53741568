// SPDX-License-Identifier: MIT
// libFuzzer target: the emulator's JSON configuration (`ballbar emulate --config`, `emulator:CONFIG`,
// device/src/emulator_config.cpp). Refused with std::invalid_argument naming the key, or accepted.
// Relative program files resolve in a directory that does not exist, so nothing is read from disk.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string_view>

#include "ballbar/device/emulator.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    if (text.find("\"/") != std::string_view::npos) return 0;  // an absolute path would read the fuzzer's disk
    try {
        (void)ballbar::device::parse_emulator_config(text, "/nonexistent/ballbar-fuzz");
    } catch (const std::invalid_argument&) {
    }
    return 0;
}
