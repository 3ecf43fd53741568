// SPDX-License-Identifier: MIT
// fileio outputs: exclusive temporary files, rename over the target, refusals by inode, no links.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include "../scratch_dir.hpp"
#include "ballbar/fileio/output.hpp"

using namespace ballbar::fileio;
namespace fs = std::filesystem;

namespace {

using Dir = ballbar::test::ScratchDir;

std::string slurp(const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

FileError::Kind kind_of(const std::function<void()>& f, std::string& message) {
    try {
        f();
    } catch (const FileError& e) {
        message = e.what();
        return e.kind();
    }
    ADD_FAILURE() << "no error";
    return FileError::Kind::failed;
}

TEST(FileioOutput, TheTargetChangesOnlyAtCommit) {
    Dir d{"fileio"};
    std::ofstream(d.file("out")) << "old";
    {
        OutputFile out(d.file("out"), "--out");
        out.write("new");
        EXPECT_EQ(slurp(d.file("out")), "old") << "untouched until commit";
        EXPECT_EQ(d.entries(), 2u) << "one temporary file beside it";
    }  // no commit: the temporary file is removed, the target kept
    EXPECT_EQ(slurp(d.file("out")), "old");
    EXPECT_EQ(d.entries(), 1u);
    write_file(d.file("out"), "--out", "new");
    EXPECT_EQ(slurp(d.file("out")), "new");
    EXPECT_EQ(d.entries(), 1u);
}

TEST(FileioOutput, PlantedTemporaryNamesAreNeitherFollowedNorDeleted) {
    Dir d{"fileio"};
    std::ofstream(d.file("victim")) << "victim";
    fs::create_symlink(d.file("victim"), d.file("out.tmp"));
    fs::create_symlink(d.file("victim"), d.file("out.part"));
    write_file(d.file("out"), "--out", "data");
    EXPECT_EQ(slurp(d.file("out")), "data");
    EXPECT_EQ(slurp(d.file("victim")), "victim");
    EXPECT_TRUE(fs::is_symlink(d.file("out.tmp")));
    EXPECT_TRUE(fs::is_symlink(d.file("out.part")));
    EXPECT_EQ(d.entries(), 4u);
}

TEST(FileioOutput, RefusesInputsByInodeLinksAndDirectories) {
    Dir d{"fileio"};
    std::ofstream(d.file("db")) << "database";
    fs::create_hard_link(d.file("db"), d.file("alias"));
    const std::vector<Protected> inputs = {{d.file("db"), "database"}};
    std::string msg;
    EXPECT_EQ(kind_of([&] { write_file(d.file("alias"), "--out", "x", inputs); }, msg), FileError::Kind::refused);
    EXPECT_NE(msg.find("is the database"), std::string::npos) << msg;
    EXPECT_EQ(slurp(d.file("db")), "database");
    fs::create_symlink(d.file("db"), d.file("link"));
    EXPECT_EQ(kind_of([&] { write_file(d.file("link"), "--out", "x"); }, msg), FileError::Kind::refused);
    EXPECT_NE(msg.find("is a symbolic link"), std::string::npos) << msg;
    EXPECT_EQ(kind_of([&] { write_file(d.path.string(), "--out", "x"); }, msg), FileError::Kind::refused);
    EXPECT_NE(msg.find("is a directory"), std::string::npos) << msg;
    EXPECT_EQ(kind_of([&] { write_file(d.file("no/such/dir/x"), "--out", "x"); }, msg), FileError::Kind::failed);
    EXPECT_EQ(slurp(d.file("db")), "database");
}

TEST(FileioOutput, KeepsPermissionsAndWritesDevicesDirectly) {
    Dir d{"fileio"};
    std::ofstream(d.file("out")) << "old";
    fs::permissions(d.file("out"), fs::perms::owner_read | fs::perms::owner_write);
    write_file(d.file("out"), "--out", "new");
    EXPECT_EQ(fs::status(d.file("out")).permissions() & fs::perms::all, fs::perms::owner_read | fs::perms::owner_write);
    write_file("/dev/null", "--out", "discarded");  // a device: written, never replaced
    EXPECT_TRUE(fs::is_character_file("/dev/null"));
}

TEST(FileioOutput, StreamsThroughAnOstream) {
    Dir d{"fileio"};
    OutputStream out(d.file("csv"), "--out");
    for (int i = 0; i < 100000; ++i) out << i << '\n';  // several 64 KiB buffers
    out.commit();
    std::istringstream back(slurp(d.file("csv")));
    int last = -1;
    for (int v = 0; back >> v;) last = v;
    EXPECT_EQ(last, 99999);
}

}  // namespace
