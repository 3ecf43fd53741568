// SPDX-License-Identifier: MIT
// Reliability: SIGKILL during acquisition, damaged and truncated files, a full disk, a newer schema,
// and a reader reading while a writer writes.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <random>
#include <thread>

#include "ballbar/storage/sample_writer.hpp"
#include "ballbar/storage/session_export.hpp"
#include "ballbar/storage/store.hpp"
#include "test_util.hpp"

namespace ballbar::storage {
namespace {

using test::slurp;
using test::TempDir;
using Kind = StorageError::Kind;

/// A running child process whose stdout is a pipe of 8-byte integers.
struct Child {
    pid_t pid = -1;
    int fd = -1;
    std::vector<std::uint64_t> values;
    std::string partial;

    void drain(std::chrono::milliseconds timeout) {
        const auto until = std::chrono::steady_clock::now() + timeout;
        while (true) {
            const auto left =
                std::chrono::duration_cast<std::chrono::milliseconds>(until - std::chrono::steady_clock::now());
            if (left.count() <= 0) return;
            pollfd p{fd, POLLIN, 0};
            if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) return;
            char buf[65536];
            const ssize_t n = ::read(fd, buf, sizeof buf);
            if (n <= 0) return;  // EOF: the child is gone
            partial.append(buf, static_cast<std::size_t>(n));
            while (partial.size() >= 8) {
                std::uint64_t v;
                std::memcpy(&v, partial.data(), 8);
                values.push_back(v);
                partial.erase(0, 8);
            }
        }
    }
};

Child spawn(const std::vector<std::string>& args) {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe");
    Child c;
    c.pid = ::fork();
    if (c.pid == 0) {
        ::dup2(fds[1], STDOUT_FILENO);
        std::vector<char*> argv;
        for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
        argv.push_back(nullptr);
        ::execv(argv[0], argv.data());
        std::_Exit(127);
    }
    ::close(fds[1]);
    c.fd = fds[0];
    return c;
}

struct Counts {
    std::int64_t n, min, max;
};

Counts seq_counts(Store& store, std::int64_t id) {
    auto st = store.db().prepare(
        "SELECT count(*), coalesce(min(seq), -1), coalesce(max(seq), -1) FROM samples WHERE session_id = ?");
    st.bind(1, id);
    st.step();
    return {st.column_int(0), st.column_int(1), st.column_int(2)};
}

/// Runs the child until a random moment, kills it with SIGKILL, and returns (session id, reported count).
std::pair<std::int64_t, std::uint64_t> run_and_kill(const std::string& db, std::mt19937& rng,
                                                    const std::string& resume = {}) {
    std::vector<std::string> args = {STORAGE_KILL_CHILD, db, STORAGE_KILL_SOURCE};
    if (!resume.empty()) args.push_back(resume);
    Child child = spawn(args);
    // Wait for the first value (session id), then a random time, then SIGKILL.
    while (child.values.empty()) {
        child.drain(std::chrono::milliseconds(100));
        int status = 0;
        if (::waitpid(child.pid, &status, WNOHANG) == child.pid) {
            ADD_FAILURE() << "child exited early";
            return {0, 0};
        }
    }
    // Let it commit several batches first (however slow a loaded or sanitized build is), then a random time.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while ((child.values.size() < 2 || child.values.back() <= 300u) && std::chrono::steady_clock::now() < deadline) {
        child.drain(std::chrono::milliseconds(20));
        int status = 0;
        if (::waitpid(child.pid, &status, WNOHANG) == child.pid) {
            ADD_FAILURE() << "child exited before committing several batches";
            return {0, 0};
        }
    }
    std::uniform_int_distribution<int> delay_ms(0, 300);
    child.drain(std::chrono::milliseconds(delay_ms(rng)));
    ::kill(child.pid, SIGKILL);
    int status = 0;
    ::waitpid(child.pid, &status, 0);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
    child.drain(std::chrono::milliseconds(1000));  // what it wrote before dying
    ::close(child.fd);
    const auto id = static_cast<std::int64_t>(child.values.front());
    const std::uint64_t reported = child.values.size() > 1 ? child.values.back() : 0;
    return {id, reported};
}

TEST(Reliability, SigkillDuringAcquisitionLosesAtMostOneBatch) {
    TempDir dir;
    const auto db = dir.file("kill.db");
    std::mt19937 rng(20261121);
    constexpr std::int64_t kBatch = 51;  // 50 ms at 1 kHz, plus the sample that closes the batch
    std::int64_t first_id = 0;
    std::int64_t before_resume = 0;
    for (int round = 0; round < 5; ++round) {
        SCOPED_TRACE("round " + std::to_string(round));
        const bool resume = round == 4;
        const auto [id, reported] = run_and_kill(db, rng, resume ? std::to_string(first_id) : std::string());
        if (round == 0) first_id = id;
        {  // Before anyone recovers it, every reader already sees it interrupted (its writer is gone).
            StoreOptions ro;
            ro.read_only = true;
            Store reader(db, ro);
            EXPECT_EQ(reader.session(id).state, SessionState::interrupted);
            EXPECT_TRUE(reader.session(id).writer_gone);
        }
        Store store(db);
        EXPECT_EQ(store.integrity_check(), "ok");
        const auto info = store.session(id);
        EXPECT_EQ(info.state, SessionState::interrupted);
        EXPECT_EQ(store.transitions(id).back().event, "interrupted: found unfinished on open");
        const Counts c = seq_counts(store, id);
        EXPECT_EQ(c.min, 0);
        EXPECT_EQ(c.max + 1, c.n) << "sequence numbers contiguous from 0";
        const std::int64_t stored = c.n - (resume ? before_resume : 0);
        EXPECT_GT(reported, 300u) << "the child ran long enough to commit several batches";
        EXPECT_GE(stored, static_cast<std::int64_t>(reported) - kBatch) << "lost more than one batch";
        EXPECT_LE(stored, static_cast<std::int64_t>(reported) + 1);
        if (round == 0) before_resume = c.n;
    }
}

TEST(Reliability, SigkillLosesAtMost100msOfWhatTheInstrumentMeasured) {
    if (std::string(STORAGE_KILL_SOURCE) != "emulator") GTEST_SKIP() << "built without the device emulator";
    TempDir dir;
    const auto db = dir.file("realtime.db");
    std::mt19937 rng(1201);
    std::uniform_int_distribution<int> delay_ms(250, 700);
    for (int round = 0; round < 3; ++round) {
        SCOPED_TRACE("round " + std::to_string(round));
        Child child = spawn({STORAGE_KILL_CHILD, db, "realtime"});
        while (child.values.size() < 3) {  // id, the device clock's zero, a first sample
            child.drain(std::chrono::milliseconds(50));
            int status = 0;
            ASSERT_NE(::waitpid(child.pid, &status, WNOHANG), child.pid) << "child exited early";
        }
        child.drain(std::chrono::milliseconds(delay_ms(rng)));
        const auto kill_at = std::chrono::steady_clock::now();
        ::kill(child.pid, SIGKILL);
        int status = 0;
        ::waitpid(child.pid, &status, 0);
        ::close(child.fd);
        const auto id = static_cast<std::int64_t>(child.values[0]);
        const auto zero_us = static_cast<std::int64_t>(child.values[1]);
        const std::int64_t measured_us =
            std::chrono::duration_cast<std::chrono::microseconds>(kill_at.time_since_epoch()).count() - zero_us;
        Store store(db);
        const auto n = store.next_seq(id);
        ASSERT_GT(n, 100u);
        const auto last = store.samples(id, n - 1, 1).at(0);
        const double lost_ms = static_cast<double>(measured_us - static_cast<std::int64_t>(last.device_time_us)) * 1e-3;
        EXPECT_GE(lost_ms, 0.0);
        EXPECT_LE(lost_ms, 100.0) << "the instrument had measured " << measured_us << " µs, the last stored "
                                  << last.device_time_us << " µs";
    }
}

void corrupt_and_expect_untouched(const std::string& path, Kind kind) {
    const std::string before = slurp(path);
    try {
        Store store(path);
        store.sessions();
        store.samples(1);
        const auto check = store.integrity_check();
        if (check != "ok") throw StorageError(Kind::corrupt, check);
        FAIL() << "a damaged database was accepted";
    } catch (const StorageError& e) {
        EXPECT_EQ(e.kind(), kind) << e.what();
        EXPECT_FALSE(std::string(e.what()).empty());
    }
    EXPECT_EQ(slurp(path), before) << "the damaged file was modified";
}

std::string make_db_reliability(const TempDir& dir, const std::string& name, int samples) {
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

TEST(Reliability, NotADatabaseIsRefusedAndUntouched) {
    TempDir dir;
    const auto path = dir.file("notes.db");
    { std::ofstream(path) << std::string(5000, 'x'); }
    corrupt_and_expect_untouched(path, Kind::corrupt);
    const auto tiny = dir.file("tiny.db");
    { std::ofstream(tiny) << "SQLite"; }
    corrupt_and_expect_untouched(tiny, Kind::corrupt);
}

TEST(Reliability, TruncatedDatabaseIsRefusedAndUntouched) {
    TempDir dir;
    const auto path = make_db_reliability(dir, "t.db", 20000);
    const auto size = std::filesystem::file_size(path);
    std::filesystem::resize_file(path, size / 2);
    try {
        Store store(path);
        FAIL();
    } catch (const StorageError& e) {
        EXPECT_EQ(e.kind(), Kind::corrupt);
        EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
    }
    corrupt_and_expect_untouched(path, Kind::corrupt);
}

TEST(Reliability, DamagedPagesAreReportedAndUntouched) {
    TempDir dir;
    const auto path = make_db_reliability(dir, "d.db", 20000);
    {
        std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
        const auto size = static_cast<std::streamoff>(std::filesystem::file_size(path));
        for (std::streamoff off = 4096 * 2; off < size; off += 4096 * 3) {  // scribble over many pages
            f.seekp(off + 8);
            f.write("\xde\xad\xbe\xef\xde\xad\xbe\xef\xff\xff\xff\xff", 12);
        }
    }
    corrupt_and_expect_untouched(path, Kind::corrupt);
}

TEST(Reliability, NewerSchemaIsRefusedAndUntouched) {
    TempDir dir;
    const auto path = make_db_reliability(dir, "new.db", 10);
    {
        Database db(path);
        db.exec("PRAGMA user_version = 99");
        db.exec("PRAGMA journal_mode = DELETE");
    }
    const std::string before = slurp(path);
    try {
        Store store(path);
        FAIL();
    } catch (const StorageError& e) {
        EXPECT_EQ(e.kind(), Kind::newer_schema);
        EXPECT_NE(std::string(e.what()).find("schema version 99"), std::string::npos) << e.what();
    }
    EXPECT_EQ(slurp(path), before);
    EXPECT_FALSE(std::filesystem::exists(path + "-wal"));
}

TEST(Reliability, ForeignSqliteDatabaseIsRefusedAndUntouched) {
    TempDir dir;
    const auto path = dir.file("other.db");
    {
        Database db(path);
        db.exec("CREATE TABLE t(x); INSERT INTO t VALUES (1)");
    }
    const std::string before = slurp(path);
    EXPECT_THROW(Store{path}, StorageError);
    EXPECT_EQ(slurp(path), before);
}

TEST(Reliability, DiskFullStopsTheWriterAndKeepsWhatWasCommitted) {
    TempDir dir;
    const auto path = dir.file("full.db");
    std::uint64_t committed = 0;
    std::int64_t id = 0;
    {
        Store store(path);
        NewSession ns;
        ns.machine = test::tttrr();
        id = store.create_session(ns);
        store.start_session(id);
        const auto pages = store.db().query_int("PRAGMA page_count");
        store.db().exec("PRAGMA max_page_count = " + std::to_string(pages + 40));
        SampleWriter w(store, id);
        try {
            for (std::uint64_t i = 0; i < 10'000'000; ++i) w.append({0, i * 1000, 1, 0, 20.0f});
            FAIL() << "the size limit was never reached";
        } catch (const StorageError& e) {
            EXPECT_EQ(e.kind(), Kind::disk_full);
            EXPECT_EQ(std::string(e.what()).rfind("disk full: ", 0), 0u) << e.what();
            EXPECT_NE(std::string(e.what()).find("samples committed before are kept"), std::string::npos);
        }
        committed = w.committed();
        EXPECT_GT(committed, 1000u);
        EXPECT_GT(w.pending(), 0u);
        store.fail_session(id, "fail: disk full");  // small writes still fit in the freed/last pages
    }
    Store store(path);
    EXPECT_EQ(store.integrity_check(), "ok");
    EXPECT_EQ(store.sample_count(id), static_cast<std::int64_t>(committed));
    EXPECT_EQ(seq_counts(store, id).max + 1, static_cast<std::int64_t>(committed));
}

TEST(Reliability, ReaderReadsWhileAWriterWrites) {
    TempDir dir;
    const auto path = dir.file("rw.db");
    std::int64_t id = 0;
    {
        Store store(path);
        NewSession ns;
        ns.machine = test::tttrr();
        id = store.create_session(ns);
    }
    StoreOptions ro;
    ro.recover = false;
    Store reader(path, ro);
    std::atomic<bool> done{false};
    std::thread writer([&] {
        StoreOptions o;
        o.sync_full = false;
        Store store(path, o);  // the creating Store closed: the session is interrupted now; resume it
        store.resume_session(id);
        SampleWriter w(store, id, {UINT64_MAX, 1000});  // batches of exactly 1000 samples
        for (std::uint64_t i = 0; i < 60'000; ++i) {
            w.append({0, i * 1000, 0, 0, 20.0f});
            if (i % 1000 == 999) std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
        w.flush();
        store.finish_session(id);
        done = true;
    });
    std::int64_t last = 0;
    int reads = 0, partial = 0;
    while (!done) {
        const auto n = reader.sample_count(id);  // never blocks the writer nor fails with busy
        EXPECT_GE(n, last);
        EXPECT_EQ(n % 1000, 0) << "a reader sees whole batches only";
        partial += n > 0 && n < 60'000;
        last = n;
        ++reads;
    }
    writer.join();
    EXPECT_GT(reads, 1);
    EXPECT_GT(partial, 0) << "the reader saw the session while it was being written";
    EXPECT_EQ(reader.sample_count(id), 60'000);
    EXPECT_EQ(reader.session(id).state, SessionState::completed);
}

/// Issue 24: a CSV export that hit a full disk left a new points.csv beside the old samples.csv. The
/// disk fills (a file-size limit, EFBIG, in a child process) while samples.csv is written: the
/// directory keeps the earlier export's two files, whole, and no temporary file.
TEST(Reliability, ACsvExportThatRunsOutOfSpaceLeavesTheEarlierExportWhole) {
    TempDir dir;
    const auto path = dir.file("e.db");
    std::int64_t small = 0;
    std::int64_t large = 0;
    {
        Store store(path);
        for (const int n : {10, 40000}) {
            NewSession ns;
            ns.machine = test::tttrr();
            const auto id = store.create_session(ns);
            store.start_session(id);
            {
                SampleWriter w(store, id);
                for (int i = 0; i < n; ++i) w.append({0, static_cast<std::uint64_t>(i) * 1000, i * 7 + n, 0, 20.0f});
            }
            store.finish_session(id);
            (n == 10 ? small : large) = id;
        }
        export_csv(store, small, dir.path() / "out");
    }
    // The earlier export, told apart from any new one.
    std::ofstream(dir.file("out/points.csv"), std::ios::app) << "0,earlier export\n";
    std::ofstream(dir.file("out/samples.csv"), std::ios::app) << "0,earlier export\n";
    const auto points = slurp(dir.file("out/points.csv"));
    const auto samples = slurp(dir.file("out/samples.csv"));
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
        ::signal(SIGXFSZ, SIG_IGN);  // a write past the limit fails with EFBIG, as on a full disk
        const rlimit lim{200 * 1024, 200 * 1024};
        ::setrlimit(RLIMIT_FSIZE, &lim);
        try {
            StoreOptions o;
            o.recover = false;
            Store store(path, o);
            export_csv(store, large, dir.path() / "out");  // samples.csv: about 1 MB
        } catch (const std::exception&) {
            ::_exit(0);  // refused, as it must be
        }
        ::_exit(1);
    }
    int st = 0;
    ::waitpid(pid, &st, 0);
    ASSERT_TRUE(WIFEXITED(st));
    EXPECT_EQ(WEXITSTATUS(st), 0) << "the export past the limit did not fail";
    EXPECT_EQ(slurp(dir.file("out/points.csv")), points) << "a new points.csv beside the old samples.csv";
    EXPECT_EQ(slurp(dir.file("out/samples.csv")), samples);
    std::size_t files = 0;
    for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir.path() / "out")) ++files;
    EXPECT_EQ(files, 2u) << "a temporary file was left behind";
}

}  // namespace
}  // namespace ballbar::storage
