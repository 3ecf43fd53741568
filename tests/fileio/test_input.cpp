// SPDX-License-Identifier: MIT
// fileio inputs: regular files only, size caps checked before reading, lines streamed with a maximum
// length, whatever the chunk boundaries.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "../scratch_dir.hpp"
#include "ballbar/fileio/input.hpp"

using namespace ballbar::fileio;
namespace fs = std::filesystem;

namespace {

using Dir = ballbar::test::ScratchDir;

std::string refusal(const std::function<void()>& f) {
    try {
        f();
    } catch (const FileError& e) {
        EXPECT_EQ(e.kind(), FileError::Kind::refused) << e.what();
        return e.what();
    }
    ADD_FAILURE() << "not refused";
    return {};
}

std::vector<std::string> lines_of(const std::string& path, std::size_t max_line = kMaxLineBytes) {
    LineReader r(InputFile::open(path, "test file"), max_line);
    std::vector<std::string> out;
    while (auto l = r.next()) out.emplace_back(*l);
    return out;
}

TEST(FileioInput, RegularFilesOnly) {
    Dir d{"fileio"};
    EXPECT_NE(refusal([&] { InputFile::open(d.path.string(), "readings file"); }).find("is a directory"),
              std::string::npos);
    EXPECT_NE(refusal([&] { InputFile::open("/dev/zero", "readings file"); }).find("a character device"),
              std::string::npos);
    ASSERT_EQ(::mkfifo((d.path / "fifo").c_str(), 0600), 0);
    const auto t0 = std::chrono::steady_clock::now();
    EXPECT_NE(refusal([&] { InputFile::open((d.path / "fifo").string(), "plan file"); }).find("a FIFO"),
              std::string::npos);
    EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(2)) << "a FIFO nobody writes never blocks";
    EXPECT_NE(refusal([&] { InputFile::open((d.path / "nope").string(), "plan file"); }).find("no such plan file"),
              std::string::npos);
}

TEST(FileioInput, SizeCapIsCheckedBeforeReading) {
    Dir d{"fileio"};
    { std::ofstream(d.path / "sparse"); }
    fs::resize_file(d.path / "sparse", 10ull << 30);  // 10 GB of holes
    const std::string msg = refusal([&] { read_whole((d.path / "sparse").string(), "machine file", kMaxJsonBytes); });
    EXPECT_NE(msg.find("too large"), std::string::npos) << msg;
    EXPECT_NE(msg.find("16 MiB"), std::string::npos) << msg;
    const std::string small = d.write("small", std::string(100, 'x'));
    EXPECT_EQ(read_whole(small, "f", 100).size(), 100u);
    EXPECT_NE(refusal([&] { read_whole(small, "f", 99); }).find("too large"), std::string::npos);
    EXPECT_EQ(read_whole(d.write("empty", ""), "f", 10), "");
    EXPECT_EQ(read_head(small, "f", 7), "xxxxxxx");
}

TEST(FileioInput, LinesWithLfCrlfAndNoFinalNewline) {
    Dir d{"fileio"};
    EXPECT_EQ(lines_of(d.write("a", "one\ntwo\r\n\nthree")), (std::vector<std::string>{"one", "two", "", "three"}));
    EXPECT_EQ(lines_of(d.write("b", "")), std::vector<std::string>{});
    EXPECT_EQ(lines_of(d.write("c", "\n")), std::vector<std::string>{""});
}

TEST(FileioInput, LinesAcrossEveryBufferBoundary) {
    Dir d{"fileio"};
    // Line lengths around the 64 KiB read size, so lines straddle every kind of boundary.
    std::string text;
    std::vector<std::string> expected;
    for (std::size_t n : {0u, 1u, 65534u, 65535u, 65536u, 65537u, 3u, 200000u, 7u}) {
        expected.emplace_back(n, static_cast<char>('a' + n % 26));
        text += expected.back() + (n % 2 ? "\r\n" : "\n");
    }
    EXPECT_EQ(lines_of(d.write("big", text)), expected);
}

// The tap (import's hash) sees the file's bytes exactly: each once, in order, line ends included,
// across the reader's buffer boundaries and with no final newline.
TEST(FileioInput, TheTapSeesEveryByteOnceInOrder) {
    Dir d{"fileio"};
    std::string text;
    for (std::size_t n : {0u, 65535u, 1u, 65536u, 200000u, 2u}) text += std::string(n, 'x') + (n % 2 ? "\r\n" : "\n");
    text += "last line without a newline";
    LineReader r(InputFile::open(d.write("t", text), "test file"));
    std::string seen;
    r.set_tap([&seen](std::string_view bytes) { seen += bytes; });
    std::size_t lines = 0;
    while (r.next()) ++lines;
    EXPECT_EQ(lines, 7u);
    EXPECT_EQ(seen, text);
}

TEST(FileioInput, ALineLongerThanTheLimitIsRefusedWithItsNumber) {
    Dir d{"fileio"};
    const std::string path = d.write("long", "ok\nok\n" + std::string(1001, 'z') + "\nok\n");
    LineReader r(InputFile::open(path, "trace file"), 1000);
    EXPECT_EQ(*r.next(), "ok");
    EXPECT_EQ(*r.next(), "ok");
    const std::string msg = refusal([&] { r.next(); });
    EXPECT_NE(msg.find("line 3 is longer than 1000 bytes"), std::string::npos) << msg;
    // Exactly the limit (with a CR) is fine; a long last line without LF is refused too.
    EXPECT_EQ(lines_of(d.write("edge", std::string(1000, 'y') + "\r\n"), 1000).at(0).size(), 1000u);
    EXPECT_NE(refusal([&] { lines_of(d.write("tail", std::string(1001, 'y')), 1000); }).find("line 1"),
              std::string::npos);
    const std::string text_msg = refusal([&] { read_text(path, "NC program", 1 << 20, 1000); });
    EXPECT_NE(text_msg.find("line 3"), std::string::npos) << text_msg;
}

TEST(FileioInput, CutKeepsUtf8Whole) {
    EXPECT_EQ(cut("short"), "short");
    EXPECT_EQ(cut(std::string(100, 'a')), std::string(40, 'a') + "…");
    const std::string mu = std::string(39, 'a') + "µµ";  // µ is 2 bytes: byte 40 is inside it
    EXPECT_EQ(cut(mu), std::string(39, 'a') + "…");
}

/// Issue 24: 16 MiB of "[" took 1.27 GB in the JSON parser before it failed. The nesting is checked
/// first, in one pass without allocating; brackets inside strings do not count.
TEST(FileioInput, JsonNestedDeeperThanTheLimitIsRefusedBeforeParsing) {
    EXPECT_NO_THROW(check_json_nesting(std::string(64, '[') + std::string(64, ']'), "model"));
    try {
        check_json_nesting(std::string(65, '['), "model");
        FAIL() << "65 levels accepted";
    } catch (const FileError& e) {
        EXPECT_EQ(e.kind(), FileError::Kind::refused);
        EXPECT_EQ(std::string(e.what()), "model: JSON nested deeper than 64 levels (at byte 65)");
    }
    EXPECT_NO_THROW(check_json_nesting(R"({"a": ")" + std::string(1000, '[') + R"(\"[", "b": [[1]]})", "x"));
    EXPECT_NO_THROW(check_json_nesting(std::string(1000, ']'), "x")) << "not JSON, but not deep: the parser says";
    EXPECT_THROW(check_json_nesting(std::string(16u << 20, '['), "plan"), FileError);
    // Flat, but too many values: 16 MiB of "0," parsed to 418 MB; refused before parsing.
    std::string flat = "[";
    for (int i = 0; i < 2'000'000; ++i) flat += "0,";
    flat += "0]";
    try {
        check_json_nesting(flat, "machine file");
        ADD_FAILURE() << "2,000,001 values were not refused";
    } catch (const FileError& e) {
        EXPECT_NE(std::string(e.what()).find("more than 2000000 values"), std::string::npos) << e.what();
    }
    EXPECT_NO_THROW(check_json_nesting(R"({"a": [1, 2, 3], "b": "x,y,[z"})", "x", kMaxJsonDepth, 6));
    EXPECT_THROW(check_json_nesting(R"({"a": [1, 2, 3], "b": "x,y,[z"})", "x", kMaxJsonDepth, 5), FileError);
}

}  // namespace
