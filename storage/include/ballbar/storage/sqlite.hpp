// SPDX-License-Identifier: MIT
// A thin RAII wrapper over the sqlite3 C API: Database (a connection), Statement (a prepared
// statement), Transaction (BEGIN … COMMIT, rolled back unless committed). Every failure throws a
// StorageError carrying SQLite's message and extended result code.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

struct sqlite3;
struct sqlite3_stmt;

namespace ballbar::storage {

/// Every error of the storage layer. `kind()` says what the caller can do about it; `sqlite_code()` is
/// SQLite's extended result code (0 when the error did not come from SQLite).
class StorageError : public std::runtime_error {
  public:
    enum class Kind {
        sqlite,        ///< any other SQLite failure
        disk_full,     ///< SQLITE_FULL: the disk or the database's size limit is full; committed data stays
        corrupt,       ///< not a database, truncated or damaged (SQLITE_CORRUPT / SQLITE_NOTADB)
        newer_schema,  ///< written by a newer ballbar; left untouched
        busy,          ///< another connection held a lock longer than the busy timeout
        not_found,     ///< no such session / model / …, or a key that matches more than one
        invalid,       ///< a request that contradicts the stored state (illegal state transition, …)
    };
    StorageError(Kind kind, const std::string& message, int sqlite_code = 0)
        : std::runtime_error(message), kind_(kind), sqlite_code_(sqlite_code) {}
    Kind kind() const { return kind_; }
    int sqlite_code() const { return sqlite_code_; }

  private:
    Kind kind_;
    int sqlite_code_;
};

class Statement;

/// One SQLite connection. Move-only; closes on destruction.
class Database {
  public:
    /// read_only_immutable: read-only, and SQLite told that nobody changes the file while it is open
    /// (URI parameter immutable=1): no lock, no -shm. For a WAL file in a directory this process cannot
    /// write and no writer has open (Store's fallback): only so can it be read there.
    enum class Mode { read_write_create, read_write, read_only, read_only_immutable };

    /// Opens `path` (":memory:" for an in-memory database). Throws StorageError.
    explicit Database(const std::string& path, Mode mode = Mode::read_write_create);
    ~Database();
    Database(Database&& other) noexcept;
    Database& operator=(Database&& other) noexcept;
    Database(const Database&) = delete;
    Database& operator=(const Database&) = delete;

    /// Runs one or more statements without results.
    void exec(std::string_view sql);
    Statement prepare(std::string_view sql);
    /// The first column of the first row of a query returning one integer (e.g. a PRAGMA).
    std::int64_t query_int(std::string_view sql);
    std::string query_text(std::string_view sql);
    std::int64_t last_insert_rowid() const;
    int changes() const;
    /// How long a statement waits for another connection's lock before failing with Kind::busy.
    void set_busy_timeout(int milliseconds);
    const std::string& path() const { return path_; }
    sqlite3* handle() const { return db_; }

    /// Throws the StorageError for result code `rc` of an operation described by `what`.
    [[noreturn]] void fail(int rc, std::string_view what) const;

  private:
    sqlite3* db_ = nullptr;
    std::string path_;
};

/// A prepared statement. Bind parameters are 1-based, columns 0-based (as in SQLite).
class Statement {
  public:
    Statement(Database& db, std::string_view sql);
    ~Statement();
    Statement(Statement&& other) noexcept;
    Statement& operator=(Statement&& other) noexcept;
    Statement(const Statement&) = delete;
    Statement& operator=(const Statement&) = delete;

    Statement& bind(int index, std::int64_t value);
    Statement& bind(int index, int value) { return bind(index, std::int64_t{value}); }
    Statement& bind(int index, double value);
    Statement& bind(int index, std::string_view text);
    Statement& bind(int index, const char* text) { return bind(index, std::string_view(text)); }
    Statement& bind(int index, const std::string& text) { return bind(index, std::string_view(text)); }
    Statement& bind_null(int index);
    template <class T>
    Statement& bind(int index, const std::optional<T>& value) {
        return value ? bind(index, *value) : bind_null(index);
    }

    /// Advances: true while a row is available, false when done. Throws on errors.
    bool step();
    /// Runs a statement that returns no rows (step once, then reset).
    void run();
    void reset();
    void clear_bindings();

    bool is_null(int column) const;
    std::int64_t column_int(int column) const;
    double column_double(int column) const;
    std::string column_text(int column) const;
    std::optional<std::int64_t> column_opt_int(int column) const;
    std::optional<double> column_opt_double(int column) const;
    std::optional<std::string> column_opt_text(int column) const;

  private:
    Database* db_ = nullptr;
    sqlite3_stmt* stmt_ = nullptr;
};

/// BEGIN (IMMEDIATE by default) on construction; ROLLBACK on destruction unless commit() was called.
/// Inside another transaction it becomes a SAVEPOINT, so library calls compose into one atomic unit.
class Transaction {
  public:
    explicit Transaction(Database& db, bool immediate = true);
    ~Transaction();
    Transaction(const Transaction&) = delete;
    Transaction& operator=(const Transaction&) = delete;
    void commit();

  private:
    Database& db_;
    bool open_ = false;
    bool nested_ = false;
};

}  // namespace ballbar::storage
