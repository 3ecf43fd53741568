// SPDX-License-Identifier: MIT
// Helpers shared by the storage tests: a fresh temporary directory per test and a sample machine.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "ballbar/analysis/types.hpp"

namespace ballbar::storage::test {

class TempDir {
  public:
    TempDir() {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        path_ = std::filesystem::temp_directory_path() /
                ("ballbar-store-" + std::to_string(::getpid()) + "-" + (info ? info->name() : "x"));
        std::filesystem::remove_all(path_);
        std::filesystem::create_directories(path_);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    std::string file(const std::string& name) const { return (path_ / name).string(); }
    const std::filesystem::path& path() const { return path_; }

  private:
    std::filesystem::path path_;
};

inline std::string slurp(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

inline analysis::MachineGeometry tttrr() {
    analysis::MachineGeometry m;
    m.type = analysis::MachineType::TTTRR;
    m.name = "DL-5X";
    m.c_offset_mm = {0, 0, -100};
    return m;
}

}  // namespace ballbar::storage::test
