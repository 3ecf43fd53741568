// SPDX-License-Identifier: MIT
// Reading a rendered PDF back with poppler's command-line tools (pdfinfo, pdftotext).
#pragma once

#include <array>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <regex>
#include <stdexcept>
#include <string>

namespace ballbar::report::testing {

inline std::string run_capture(const std::string& command) {
    std::unique_ptr<FILE, int (*)(FILE*)> pipe(::popen(command.c_str(), "r"), ::pclose);
    if (!pipe) throw std::runtime_error("cannot run " + command);
    std::string out;
    std::array<char, 4096> buf{};
    std::size_t n;
    while ((n = std::fread(buf.data(), 1, buf.size(), pipe.get())) > 0) out.append(buf.data(), n);
    return out;
}

inline std::string quoted(const std::filesystem::path& p) {
    return "'" + p.string() + "'";
}

/// Page count as pdfinfo reports it (-1 when it cannot read the file).
inline int pdf_pages(const std::filesystem::path& pdf) {
    const std::string info = run_capture("pdfinfo " + quoted(pdf) + " 2>/dev/null");
    std::smatch m;
    if (!std::regex_search(info, m, std::regex("Pages:\\s+(\\d+)"))) return -1;
    return std::stoi(m[1]);
}

inline std::string pdf_page_size(const std::filesystem::path& pdf) {
    const std::string info = run_capture("pdfinfo " + quoted(pdf) + " 2>/dev/null");
    std::smatch m;
    if (!std::regex_search(info, m, std::regex("Page size:\\s+([^\\n]+)"))) return {};
    return m[1];
}

inline std::string pdf_text(const std::filesystem::path& pdf) {
    return run_capture("pdftotext -layout " + quoted(pdf) + " - 2>/dev/null");
}

/// A scratch directory removed at the end of the test.
struct TempDir {
    std::filesystem::path path;
    TempDir() {
        std::string tmpl = (std::filesystem::temp_directory_path() / "ballbar-report-XXXXXX").string();
        if (!::mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
        path = tmpl;
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
};

}  // namespace ballbar::report::testing
