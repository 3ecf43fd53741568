// SPDX-License-Identifier: MIT
// Issue 15, item 4: processes that first open a new database at the same moment all succeed (one
// creates the schema, the others find it); a file that fails SQLite's quick check is refused for
// writing, untouched, with how to save what can be read, while reading it stays possible.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "ballbar/storage/sample_writer.hpp"
#include "ballbar/storage/store.hpp"
#include "test_util.hpp"

namespace ballbar::storage {
namespace {

using test::TempDir;
using Kind = StorageError::Kind;

/// Forks `n` children that wait on one pipe (so they start together), open `path` for writing and
/// create a session; returns each child's error ("" when it succeeded).
std::vector<std::string> open_at_once(const std::string& path, int n) {
    int go[2];
    if (::pipe(go) != 0) throw std::runtime_error("pipe");
    std::vector<std::pair<pid_t, int>> children;
    for (int i = 0; i < n; ++i) {
        int err[2];
        if (::pipe(err) != 0) throw std::runtime_error("pipe");
        const pid_t pid = ::fork();
        if (pid == 0) {
            ::close(go[1]);
            ::close(err[0]);
            char c;
            (void)!::read(go[0], &c, 1);  // released all at once when the parent closes its end
            std::string what;
            try {
                Store store(path);
                NewSession ns;
                ns.machine = test::tttrr();
                ns.operator_name = "child " + std::to_string(i);
                const auto id = store.create_session(ns);
                store.start_session(id);
                store.finish_session(id);
            } catch (const std::exception& e) {
                what = e.what();
                if (what.empty()) what = "(empty message)";
            }
            (void)!::write(err[1], what.data(), what.size());
            ::_exit(what.empty() ? 0 : 1);
        }
        ::close(err[1]);
        children.emplace_back(pid, err[0]);
    }
    ::close(go[0]);
    ::close(go[1]);
    std::vector<std::string> errors;
    for (const auto& [pid, fd] : children) {
        std::string what;
        std::array<char, 512> buf{};
        for (ssize_t r; (r = ::read(fd, buf.data(), buf.size())) > 0;) what.append(buf.data(), static_cast<size_t>(r));
        ::close(fd);
        int status = 0;
        ::waitpid(pid, &status, 0);
        if (what.empty() && !(WIFEXITED(status) && WEXITSTATUS(status) == 0)) what = "child died";
        errors.push_back(what);
    }
    return errors;
}

TEST(ConcurrentOpen, EightProcessesFirstOpenANewDatabaseAndAllSucceed) {
    TempDir dir;
    constexpr int kProcesses = 8;
    for (int round = 0; round < 10; ++round) {
        SCOPED_TRACE("round " + std::to_string(round));
        const std::string path = dir.file("new-" + std::to_string(round) + ".db");
        const auto errors = open_at_once(path, kProcesses);
        for (const auto& e : errors) EXPECT_EQ(e, "") << "a concurrent first open failed";
        StoreOptions ro;
        ro.read_only = true;
        Store store(path, ro);
        EXPECT_EQ(store.schema_version(), Store::kSchemaVersion);
        EXPECT_EQ(store.sessions().size(), static_cast<std::size_t>(kProcesses));
        EXPECT_EQ(store.integrity_check(), "ok");
    }
}

TEST(ConcurrentOpen, AnEmptyFileOpenedByManyAtOnceIsCreatedOnce) {
    TempDir dir;
    const std::string path = dir.file("empty.db");
    { std::ofstream(path).flush(); }  // `touch new.db`: a zero-byte file is a new database
    const auto errors = open_at_once(path, 8);
    for (const auto& e : errors) EXPECT_EQ(e, "");
    Store store(path);
    EXPECT_EQ(store.sessions().size(), 8u);
}

std::string make_db(const TempDir& dir, const std::string& name, int samples) {
    const auto path = dir.file(name);
    StoreOptions o;
    o.sync_full = false;
    Store store(path, o);
    NewSession ns;
    ns.machine = test::tttrr();
    const auto id = store.create_session(ns);
    store.start_session(id);
    {
        SampleWriter w(store, id);
        for (int i = 0; i < samples; ++i) w.append({0, static_cast<std::uint64_t>(i) * 1000, i * 7, 0, 20.0f});
    }
    store.finish_session(id);
    store.db().exec("PRAGMA wal_checkpoint(TRUNCATE)");
    return path;
}

/// Overwrites an index page's cell pointers in the samples table's index: the b-tree is damaged (the
/// quick check sees it), while the sessions table and page 1 stay readable.
void damage_last_pages(const std::string& path, int pages) {
    const auto size = static_cast<std::streamoff>(std::filesystem::file_size(path));
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    for (int k = 1; k <= pages; ++k) {
        f.seekp(size - 4096 * k + 8);
        f.write("\xde\xad\xbe\xef\xde\xad\xbe\xef\xff\xff\xff\xff", 12);
    }
}

TEST(QuickCheck, ADamagedDatabaseIsRefusedForWritingUntouchedAndStillReadable) {
    TempDir dir;
    const auto path = make_db(dir, "d.db", 20000);
    damage_last_pages(path, 3);
    const std::string before = test::slurp(path);
    try {
        Store store(path);
        FAIL() << "a database that fails the quick check was opened for writing";
    } catch (const StorageError& e) {
        EXPECT_EQ(e.kind(), Kind::corrupt);
        const std::string what = e.what();
        EXPECT_NE(what.find("fails SQLite's quick check"), std::string::npos) << what;
        EXPECT_NE(what.find("will not write"), std::string::npos) << what;
        EXPECT_NE(what.find("export ID --out ID.csv"), std::string::npos) << what;  // how to save what is readable
        EXPECT_NE(what.find(".dump"), std::string::npos) << what;
    }
    EXPECT_EQ(test::slurp(path), before) << "the refused file was modified";
    EXPECT_FALSE(std::filesystem::exists(path + "-wal"));

    // Reading stays possible: the sessions table is intact.
    StoreOptions ro;
    ro.read_only = true;
    Store reader(path, ro);
    const auto sessions = reader.sessions();
    ASSERT_EQ(sessions.size(), 1u);
    EXPECT_EQ(sessions[0].state, SessionState::completed);
    EXPECT_NE(reader.damage().find("fails SQLite's quick check"), std::string::npos)
        << "a reader must know that what it read may be incomplete";
    EXPECT_EQ(test::slurp(path), before);

    // A reader's open without recovery (`sessions`, `export`) reads it too, and knows the same.
    StoreOptions so;
    so.recover = false;
    Store listing(path, so);
    EXPECT_EQ(listing.sessions().size(), 1u);
    EXPECT_NE(listing.damage().find("fails SQLite's quick check"), std::string::npos);
    EXPECT_EQ(test::slurp(path), before);
}

TEST(QuickCheck, AReaderOfADamagedOldSchemaFileReadsItReadOnly) {
    TempDir dir;
    const auto path = make_db(dir, "old.db", 20000);
    {
        Database db(path);
        db.exec("PRAGMA user_version = 3");  // a migration would write to it
    }
    damage_last_pages(path, 3);
    const std::string before = test::slurp(path);
    StoreOptions so;
    so.recover = false;
    Store reader(path, so);
    EXPECT_EQ(reader.schema_version(), 3);
    EXPECT_FALSE(reader.damage().empty());
    EXPECT_EQ(reader.sessions().size(), 1u);
    NewSession ns;
    ns.machine = test::tttrr();
    EXPECT_THROW(reader.create_session(ns), StorageError);  // read-only
    EXPECT_EQ(test::slurp(path), before);
}

TEST(QuickCheck, AnIntactDatabaseOpensForWriting) {
    TempDir dir;
    const auto path = make_db(dir, "ok.db", 1000);
    Store store(path);
    EXPECT_EQ(store.sessions().size(), 1u);
    StoreOptions so;
    so.recover = false;
    EXPECT_EQ(Store(path, so).damage(), "");
}

}  // namespace
}  // namespace ballbar::storage
