// SPDX-License-Identifier: MIT
// Store: opening (file checks, migrations, WAL), session lifecycle with ownership locks, and recovery.
#include "ballbar/storage/store.hpp"

#include <fcntl.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <random>
#include <thread>

#include "ballbar/storage/machine_json.hpp"
#include "schema.hpp"
#include "uuid.hpp"

namespace ballbar::storage {
namespace {

using Kind = StorageError::Kind;

constexpr std::array<std::string_view, 6> kStateNames = {"created", "running", "completed",
                                                         "aborted", "failed",  "interrupted"};
constexpr std::array<std::string_view, 3> kSourceNames = {"device", "emulator", "imported"};

std::uint32_t be32(const unsigned char* p) {
    return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}

bool is_memory(const std::string& path) {
    return path.empty() || path == ":memory:" || path.rfind("file::memory:", 0) == 0;
}

/// The directory `path` is in, as access(2) wants it.
std::string directory_of(const std::string& path) {
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    return parent.empty() ? std::string(".") : parent.string();
}

/// A read of a WAL file failed because its -shm index could not be made: the directory is not writable
/// by this process and no -wal (no writer) is there.
bool unreadable_without_shm(const StorageError& e, const std::string& path) {
    const int primary = e.sqlite_code() & 0xff;
    if (primary != SQLITE_READONLY && primary != SQLITE_CANTOPEN) return false;
    std::error_code ec;
    return ::access(directory_of(path).c_str(), W_OK) != 0 && !std::filesystem::exists(path + "-wal", ec);
}

/// A reader's open (no recovery) of a file this process may not write — the file or its directory
/// read-only to it — is a read-only open: WAL mode, the lock file and a migration would need writing.
StoreOptions reader_options(StoreOptions o, const std::string& path) {
    if (o.read_only || is_memory(path)) return o;
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) return o;
    const bool file_writable = ::access(path.c_str(), W_OK) == 0;
    const bool dir_writable = ::access(directory_of(path).c_str(), W_OK) == 0;
    if (file_writable && dir_writable) return o;
    if (!o.recover) {
        o.read_only = true;
        return o;
    }
    // A writer: said plainly here, not as SQLite's "attempt to write a readonly database" later.
    throw StorageError(StorageError::Kind::sqlite,
                       !file_writable
                           ? "the database " + path +
                                 " is read-only to this user; this command writes to it "
                                 "(sessions, report and export only read)"
                           : "the directory of the database " + path +
                                 " is not writable by this user; this command writes to the database, "
                                 "which needs its journal beside it (sessions, report and export only read)");
}

/// Refuses (throws) a file written by a newer ballbar, or by another application.
void check_identity(Database& db, const std::string& path) {
    const std::int64_t version = db.query_int("PRAGMA user_version");
    const std::int64_t app_id = db.query_int("PRAGMA application_id");
    if (version > Store::kSchemaVersion) {
        throw StorageError(Kind::newer_schema, path + " has schema version " + std::to_string(version) +
                                                   ", newer than this ballbar understands (" +
                                                   std::to_string(Store::kSchemaVersion) +
                                                   "); upgrade ballbar. The file was not changed.");
    }
    if (app_id != 0 && app_id != Store::kApplicationId) {
        throw StorageError(Kind::invalid, path + " is an SQLite database of another application; not changed");
    }
    if (app_id == 0 && db.query_int("SELECT count(*) FROM sqlite_schema") > 0) {
        throw StorageError(Kind::invalid, path + " is an SQLite database but not a ballbar one; not changed");
    }
}

/// What to say about a file that fails the quick check: refused for writing, and how to save what can
/// still be read. (Debian's sqlite3 has no working `.recover`: its library lacks the sqlite_dbpage
/// table; `.dump` copies every row it can read and ends with ROLLBACK when it met damage.)
std::string damaged_message(const std::string& path, const std::string& problems, std::int64_t version) {
    return path + " is damaged: it fails SQLite's quick check (" + problems +
           "). ballbar will not write to it (the file was not changed); `ballbar sessions`, `sessions show`, "
           "`export` and `report` still read it as far as the damage allows. To save what can be read into a "
           "new database, export each session (`ballbar --db " +
           path + " export ID --out ID.csv`, then `ballbar --db NEW.db import ID.csv`), or copy every readable row: " +
           "`(sqlite3 " + path +
           " .dump | sed 's/^ROLLBACK; -- due to errors$/COMMIT;/'; echo 'PRAGMA user_version = " +
           std::to_string(version) + "; PRAGMA application_id = " + std::to_string(Store::kApplicationId) +
           ";') | sqlite3 NEW.db`. Keep " + path + " until NEW.db is checked.";
}

/// SQLite's quick check (the b-trees, their pages and order; not the index contents): "" when it
/// passes, else the message that refuses the file for writing.
std::string quick_check(Database& db, const std::string& path) {
    if (is_memory(path)) return {};
    const std::int64_t version = db.query_int("PRAGMA user_version");  // read before (check_identity)
    std::string problems;
    int count = 0;
    try {
        auto st = db.prepare("PRAGMA quick_check(3)");
        while (st.step()) {
            const std::string line = st.column_text(0);
            if (line == "ok") break;
            problems += (count++ ? "; " : "") + line;
        }
    } catch (const StorageError& e) {
        if (e.kind() != Kind::corrupt) throw;
        problems = e.what();
        count = 1;
    }
    if (count == 0) return {};
    return damaged_message(path, problems, version);
}

void set_wal(Database& db, int busy_timeout_ms) {
    // Switching to WAL takes an exclusive lock; another process opening the file at the same moment can
    // make it fail at once with "database is locked" (the busy handler is not always consulted): retry
    // until the busy timeout is over.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(busy_timeout_ms);
    for (;;) {
        try {
            if (db.query_text("PRAGMA journal_mode = WAL") == "wal") return;
        } catch (const StorageError& e) {
            if (e.kind() != Kind::busy || std::chrono::steady_clock::now() >= deadline) throw;
        }
        if (std::chrono::steady_clock::now() >= deadline)
            throw StorageError(Kind::busy, "cannot switch " + db.path() + " to WAL mode: it stays locked");
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
}

}  // namespace

std::string_view to_string(SessionState state) {
    return kStateNames[static_cast<std::size_t>(state)];
}

std::optional<SessionState> parse_session_state(std::string_view text) {
    for (std::size_t i = 0; i < kStateNames.size(); ++i) {
        if (kStateNames[i] == text) return static_cast<SessionState>(i);
    }
    return std::nullopt;
}

std::string_view to_string(SessionSource source) {
    return kSourceNames[static_cast<std::size_t>(source)];
}

std::optional<SessionSource> parse_session_source(std::string_view text) {
    for (std::size_t i = 0; i < kSourceNames.size(); ++i) {
        if (kSourceNames[i] == text) return static_cast<SessionSource>(i);
    }
    return std::nullopt;
}

bool transition_allowed(SessionState from, SessionState to) {
    using S = SessionState;
    switch (from) {
        case S::created:
            return to == S::running || to == S::aborted || to == S::interrupted || to == S::completed;
        case S::running:
            return to == S::completed || to == S::aborted || to == S::failed || to == S::interrupted;
        case S::interrupted:
            return to == S::running || to == S::completed || to == S::aborted;
        case S::failed:
            return to == S::running;  // resumed: what it measured stays, the procedure continues
        case S::completed:
        case S::aborted:
            return false;
    }
    return false;
}

Store::Store(const std::string& path, StoreOptions options)
    : options_(reader_options(std::move(options), path)),
      db_((check_file(path), path),
          options_.read_only ? Database::Mode::read_only : Database::Mode::read_write_create) {
    if (!options_.clock) options_.clock = [] { return std::chrono::system_clock::now(); };
    db_.set_busy_timeout(options_.busy_timeout_ms);

    // Read-only checks first: nothing may be written to a file we refuse. In one read transaction, so
    // that the three reads see one state of a file another process is creating.
    try {
        Transaction read(db_, false);
        check_identity(db_, path);
        read.commit();
    } catch (const StorageError& e) {
        // A WAL file is read through its -shm index, made beside it on the first open. In a directory
        // this process cannot write (an archive, another user's files), no -shm can be made; when no
        // -wal is there either, no writer has the file open, and it is read as immutable.
        if (!options_.read_only || !unreadable_without_shm(e, path)) throw;
        db_ = Database(path, Database::Mode::read_only_immutable);
        Transaction read(db_, false);
        check_identity(db_, path);
        read.commit();
    }
    if (options_.read_only) {  // an older schema is read as it is (see transitions())
        damage_ = quick_check(db_, path);
        schema_version_ = static_cast<int>(db_.query_int("PRAGMA user_version"));
        if (!is_memory(path)) probe_fd_ = ::open((path + ".lock").c_str(), O_RDONLY | O_CLOEXEC);
        return;
    }
    // The quick check reads the whole file (about 1 s of CPU for 10 M samples, 260 MB). Every open pays
    // it: one that writes (measure, import, demo, a resume) so as never to write into damage; one that
    // reads (no recovery: `sessions`, `export`, `circle analyze`; or read-only: `report`) so as never to
    // show what it read of a damaged file as if it were whole (issue 24: a bit flip listed 17,841 of
    // 178,653 samples without a word).
    const bool reader = !options_.recover;
    if (const std::string damage = quick_check(db_, path); !damage.empty()) {
        // Refused for writing. A reader's open reads it read-only instead, so that what can be read can
        // be saved, and its caller says that what it read may be incomplete.
        if (!reader) throw StorageError(Kind::corrupt, damage);
        damage_ = damage;
        options_.read_only = true;
        db_ = Database(path, Database::Mode::read_only);
        db_.set_busy_timeout(options_.busy_timeout_ms);
        schema_version_ = static_cast<int>(db_.query_int("PRAGMA user_version"));
        probe_fd_ = ::open((path + ".lock").c_str(), O_RDONLY | O_CLOEXEC);
        return;
    }

    if (!is_memory(path)) {
        set_wal(db_, options_.busy_timeout_ms);
        lock_fd_ = ::open((path + ".lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (lock_fd_ < 0) {
            throw StorageError(Kind::sqlite, "cannot open the session lock file " + path + ".lock");
        }
    }
    db_.exec(options_.sync_full ? "PRAGMA synchronous = FULL" : "PRAGMA synchronous = NORMAL");
    detail::register_uuid_function(db_.handle());
    {
        // The schema is created (or migrated) under the write lock, and the checks are made again under
        // it: of several processes that first open a new file at once, one creates the tables, the others
        // wait for it (busy timeout) and then find them, instead of creating them a second time.
        Transaction tx(db_);  // BEGIN IMMEDIATE
        check_identity(db_, path);
        migrate();
        tx.commit();
    }
    // After the migrations: v7 rebuilds a table others refer to, which SQLite allows with foreign keys
    // off only (migrate() checks them before each commit). The pragma is a no-op inside a transaction.
    db_.exec("PRAGMA foreign_keys = ON");
    schema_version_ = kSchemaVersion;
    if (options_.recover) recover_unfinished();
}

Store::~Store() {
    if (lock_fd_ >= 0) ::close(lock_fd_);  // releases every session lock of this Store
    if (probe_fd_ >= 0) ::close(probe_fd_);
}

void Store::check_file(const std::string& path) const {
    if (is_memory(path)) return;
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) {
        if (options_.read_only) throw StorageError(Kind::not_found, "no database at " + path);
        return;
    }
    const auto status = std::filesystem::status(path, ec);
    if (std::filesystem::is_directory(status))
        throw StorageError(Kind::corrupt, "the database " + path + " is a directory");
    if (!ec && !std::filesystem::is_regular_file(status))  // a FIFO or /dev/zero would block or never end
        throw StorageError(Kind::corrupt, "the database " + path + " is not a regular file; not changed");
    auto size = std::filesystem::file_size(path, ec);
    if (ec) throw StorageError(Kind::sqlite, "cannot read " + path + ": " + ec.message());
    if (size == 0) return;  // an empty file is a new database
    if (size < 100) {
        throw StorageError(Kind::corrupt,
                           path + " is not a ballbar database (only " + std::to_string(size) + " bytes); not changed");
    }
    // Another process may be checkpointing this very file (many first opens at once): it writes the
    // header's new page count before the pages it counts, and removes the WAL after. So the WAL is
    // looked at first and the size last, and a file that looks truncated is looked at again: a
    // truncated file stays so, a file being written does not.
    std::uint64_t expected = 0;
    for (int look = 0; look < 5; ++look) {
        if (look > 0) std::this_thread::sleep_for(std::chrono::milliseconds(50));
        const auto wal_size = std::filesystem::file_size(path + "-wal", ec);
        const bool wal_pending = !ec && wal_size > 0;
        std::array<unsigned char, 100> header{};
        std::ifstream in(path, std::ios::binary);
        in.read(reinterpret_cast<char*>(header.data()), header.size());
        if (!in) throw StorageError(Kind::sqlite, "cannot read " + path);
        if (std::string_view(reinterpret_cast<const char*>(header.data()), 16) !=
            std::string_view("SQLite format 3\0", 16)) {
            throw StorageError(Kind::corrupt, path + " is not an SQLite database (bad header); not changed");
        }
        std::uint32_t page_size = (std::uint32_t{header[16]} << 8) | header[17];
        if (page_size == 1) page_size = 65536;
        const std::uint32_t pages = be32(&header[28]);
        const bool size_valid = be32(&header[92]) == be32(&header[24]);
        const auto now = std::filesystem::file_size(path, ec);
        if (ec) throw StorageError(Kind::sqlite, "cannot read " + path + ": " + ec.message());
        expected = std::uint64_t{pages} * page_size;
        // A crash during a checkpoint can leave the header ahead of the file; the WAL then still holds the pages.
        if (!size_valid || wal_pending || expected <= now) return;
        size = now;
    }
    throw StorageError(Kind::corrupt, path + " is truncated (" + std::to_string(size) + " of " +
                                          std::to_string(expected) + " bytes); not changed");
}

void Store::migrate() {
    const auto version = static_cast<std::size_t>(db_.query_int("PRAGMA user_version"));
    for (std::size_t v = version; v < detail::kMigrations.size(); ++v) {
        Transaction tx(db_);
        db_.exec(detail::kMigrations[v]);
        // v7 rebuilt machines, to which sessions refer.
        if (auto check = db_.prepare("PRAGMA foreign_key_check(sessions)"); check.step())
            throw StorageError(Kind::corrupt, "migrating " + path() + " to schema v" + std::to_string(v + 1) +
                                                  " would break session " + std::to_string(check.column_int(1)) +
                                                  "'s machine; nothing was changed");
        db_.exec("PRAGMA user_version = " + std::to_string(v + 1));
        db_.exec("PRAGMA application_id = " + std::to_string(kApplicationId));
        tx.commit();
    }
}

bool Store::try_lock_session(std::int64_t id) {
    if (lock_fd_ < 0) return true;
    struct flock fl {};
    fl.l_type = F_WRLCK;
    fl.l_whence = SEEK_SET;
    fl.l_start = static_cast<off_t>(id);
    fl.l_len = 1;
    if (::fcntl(lock_fd_, F_OFD_SETLK, &fl) != 0) return false;
    if (std::find(owned_.begin(), owned_.end(), id) == owned_.end()) owned_.push_back(id);
    return true;
}

void Store::unlock_session(std::int64_t id) {
    owned_.erase(std::remove(owned_.begin(), owned_.end(), id), owned_.end());
    if (lock_fd_ < 0) return;
    struct flock fl {};
    fl.l_type = F_UNLCK;
    fl.l_whence = SEEK_SET;
    fl.l_start = static_cast<off_t>(id);
    fl.l_len = 1;
    ::fcntl(lock_fd_, F_OFD_SETLK, &fl);
}

bool Store::writer_alive(std::int64_t id) {
    if (std::find(owned_.begin(), owned_.end(), id) != owned_.end()) return true;
    if (is_memory(path())) return true;  // one process: nobody else can have written it
    const int fd = lock_fd_ >= 0 ? lock_fd_ : probe_fd_;
    if (fd < 0) return false;  // no lock file: nobody ever held a session's lock
    struct flock fl {};
    fl.l_type = F_RDLCK;  // conflicts with the writer's write lock; needs no write access
    fl.l_whence = SEEK_SET;
    fl.l_start = static_cast<off_t>(id);
    fl.l_len = 1;
    if (::fcntl(fd, F_OFD_GETLK, &fl) != 0) return true;  // cannot tell: do not call it dead
    return fl.l_type != F_UNLCK;
}

void Store::recover_unfinished() {
    Transaction tx(db_);
    std::vector<std::int64_t> ids;
    {
        auto st = db_.prepare("SELECT id FROM sessions WHERE state IN ('created', 'running') ORDER BY id");
        while (st.step()) ids.push_back(st.column_int(0));
    }
    std::vector<std::int64_t> orphaned;
    for (const auto id : ids) {
        if (lock_fd_ >= 0 && try_lock_session(id)) orphaned.push_back(id);  // no live owner holds it
    }
    for (const auto id : orphaned) transition(id, SessionState::interrupted, "interrupted: found unfinished on open");
    tx.commit();
    recovered_ = orphaned;
}

std::string Store::now_iso8601() const {
    const auto now = options_.clock();
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count();
    const std::time_t secs = static_cast<std::time_t>(ms / 1000);
    std::tm tm{};
    gmtime_r(&secs, &tm);
    char buf[96];
    std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday,
                  tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<int>(ms % 1000));
    return buf;
}

std::string Store::integrity_check() {
    auto st = db_.prepare("PRAGMA integrity_check");
    std::string out;
    while (st.step()) {
        if (!out.empty()) out += '\n';
        out += st.column_text(0);
    }
    return out;
}

std::string Store::new_uuid() {
    return detail::random_uuid();
}

std::int64_t Store::upsert_machine(const analysis::MachineGeometry& machine) {
    const std::string json = machine_to_json(machine);
    auto find = db_.prepare("SELECT id FROM machines WHERE geometry_json = ? AND asset_id IS NULL");
    find.bind(1, json);
    if (find.step()) return find.column_int(0);
    auto ins = db_.prepare("INSERT INTO machines(uuid, name, type, geometry_json) VALUES (?, ?, ?, ?)");
    ins.bind(1, new_uuid()).bind(2, machine.name).bind(3, analysis::to_string(machine.type)).bind(4, json).run();
    return db_.last_insert_rowid();
}

std::int64_t Store::upsert_instrument(const Instrument& in) {
    auto find = db_.prepare(
        "SELECT id FROM instruments WHERE model = ? AND serial = ? AND firmware = ? AND calibrated_length_mm IS ? "
        "AND calibration_date = ? AND extra_json = ?");
    find.bind(1, in.model).bind(2, in.serial).bind(3, in.firmware).bind(4, in.calibrated_length_mm);
    find.bind(5, in.calibration_date).bind(6, in.extra_json);
    if (find.step()) return find.column_int(0);
    auto ins = db_.prepare(
        "INSERT INTO instruments(model, serial, firmware, calibrated_length_mm, calibration_date, extra_json) "
        "VALUES (?, ?, ?, ?, ?, ?)");
    ins.bind(1, in.model).bind(2, in.serial).bind(3, in.firmware).bind(4, in.calibrated_length_mm);
    ins.bind(5, in.calibration_date).bind(6, in.extra_json).run();
    return db_.last_insert_rowid();
}

std::int64_t Store::create_session(const NewSession& s) {
    Transaction tx(db_);
    std::int64_t machine_id = 0;
    if (s.machine_asset.empty()) {
        machine_id = upsert_machine(s.machine);
    } else {
        const MachineEntry m = machine(s.machine_asset);
        if (m.geometry_json != machine_to_json(s.machine))
            throw StorageError(Kind::invalid, "the session's geometry is not machine " + s.machine_asset +
                                                  "'s as registered (ballbar machines show " + s.machine_asset + ")");
        machine_id = m.id;
    }
    std::optional<std::int64_t> instrument_id;
    if (s.instrument) instrument_id = upsert_instrument(*s.instrument);
    const std::string now = now_iso8601();
    auto ins = db_.prepare(
        "INSERT INTO sessions(uuid, machine_id, instrument_id, source, state, operator, procedure, notes, "
        "started_at, metadata_json) VALUES (?, ?, ?, ?, 'created', ?, ?, ?, ?, ?)");
    ins.bind(1, new_uuid()).bind(2, machine_id).bind(3, instrument_id).bind(4, to_string(s.source));
    ins.bind(5, s.operator_name).bind(6, s.procedure).bind(7, s.notes);
    ins.bind(8, s.started_at.empty() ? now : s.started_at).bind(9, s.metadata_json).run();
    const std::int64_t id = db_.last_insert_rowid();
    auto tr = db_.prepare(
        "INSERT INTO session_transitions(session_id, from_state, to_state, event, at) VALUES (?, NULL, 'created', "
        "'create', ?)");
    tr.bind(1, id).bind(2, now).run();
    // Own the session before anyone can see it, so a concurrent open does not take it for orphaned.
    if (!try_lock_session(id)) throw StorageError(Kind::invalid, "cannot lock new session " + std::to_string(id));
    tx.commit();
    return id;
}

SessionState Store::state_of(std::int64_t session_id) {
    auto st = db_.prepare("SELECT state FROM sessions WHERE id = ?");
    st.bind(1, session_id);
    if (!st.step()) throw StorageError(Kind::not_found, "no session " + std::to_string(session_id));
    const auto state = parse_session_state(st.column_text(0));
    if (!state) throw StorageError(Kind::corrupt, "session " + std::to_string(session_id) + " has an unknown state");
    return *state;
}

void Store::transition(std::int64_t session_id, SessionState to, std::string_view event) {
    Transaction tx(db_);
    const SessionState from = state_of(session_id);
    if (!transition_allowed(from, to)) {
        throw StorageError(Kind::invalid, "session " + std::to_string(session_id) + " cannot go from " +
                                              std::string(to_string(from)) + " to " + std::string(to_string(to)));
    }
    if ((to == SessionState::running || to == SessionState::created) && !try_lock_session(session_id)) {
        throw StorageError(Kind::invalid,
                           "session " + std::to_string(session_id) + " is being written by another process");
    }
    const std::string now = now_iso8601();
    const bool ends = to == SessionState::completed || to == SessionState::aborted || to == SessionState::failed;
    auto up = db_.prepare(
        "UPDATE sessions SET state = ?, ended_at = CASE WHEN ? THEN ? WHEN ? THEN NULL ELSE ended_at END WHERE id = ?");
    up.bind(1, to_string(to)).bind(2, ends ? 1 : 0).bind(3, now).bind(4, to == SessionState::running ? 1 : 0);
    up.bind(5, session_id).run();
    auto tr = db_.prepare(
        "INSERT INTO session_transitions(session_id, from_state, to_state, event, at) VALUES (?, ?, ?, ?, ?)");
    tr.bind(1, session_id).bind(2, to_string(from)).bind(3, to_string(to)).bind(4, event).bind(5, now).run();
    tx.commit();
    if (to != SessionState::running && to != SessionState::created) unlock_session(session_id);
}

std::uint64_t Store::resume_session(std::int64_t id) {
    SessionState state = state_of(id);
    if (state == SessionState::created || state == SessionState::running) {
        if (writer_alive(id)) {
            throw StorageError(Kind::invalid, "session " + std::to_string(id) +
                                                  " is being written by a running process; it cannot be resumed");
        }
        transition(id, SessionState::interrupted, "interrupted: its writer is gone");
        state = SessionState::interrupted;
    }
    if (state != SessionState::interrupted && state != SessionState::failed) {
        throw StorageError(Kind::invalid, "session " + std::to_string(id) + " is " + std::string(to_string(state)) +
                                              "; only an unfinished (interrupted or failed) session can be resumed");
    }
    transition(id, SessionState::running, state == SessionState::failed ? "resume after fail" : "resume");
    return next_seq(id);
}

void Store::set_instrument(std::int64_t session_id, const Instrument& instrument) {
    Transaction tx(db_);
    const std::int64_t instrument_id = upsert_instrument(instrument);
    auto st = db_.prepare("UPDATE sessions SET instrument_id = ? WHERE id = ?");
    st.bind(1, instrument_id).bind(2, session_id).run();
    if (db_.changes() == 0) throw StorageError(Kind::not_found, "no session " + std::to_string(session_id));
    tx.commit();
}

void Store::set_notes(std::int64_t session_id, std::string_view notes) {
    auto st = db_.prepare("UPDATE sessions SET notes = ? WHERE id = ?");
    st.bind(1, notes).bind(2, session_id).run();
    if (db_.changes() == 0) throw StorageError(Kind::not_found, "no session " + std::to_string(session_id));
}

}  // namespace ballbar::storage
