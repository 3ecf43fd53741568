// SPDX-License-Identifier: MIT
#include "ballbar/storage/sqlite.hpp"

#include <sqlite3.h>

#include <utility>

namespace ballbar::storage {
namespace {

StorageError::Kind kind_of(int rc) {
    switch (rc & 0xff) {
        case SQLITE_FULL:
            return StorageError::Kind::disk_full;
        case SQLITE_CORRUPT:
        case SQLITE_NOTADB:
            return StorageError::Kind::corrupt;
        case SQLITE_BUSY:
        case SQLITE_LOCKED:
            return StorageError::Kind::busy;
        default:
            return StorageError::Kind::sqlite;
    }
}

std::string describe(int rc, std::string_view what, std::string_view path, const char* detail) {
    std::string msg;
    switch (rc & 0xff) {
        case SQLITE_FULL:
            msg = "disk full: ";
            break;
        case SQLITE_CORRUPT:
        case SQLITE_NOTADB:
            msg = "damaged database: ";
            break;
        case SQLITE_BUSY:
        case SQLITE_LOCKED:
            msg = "database busy: ";
            break;
        default:
            break;
    }
    msg += std::string(what);
    if (!path.empty()) msg += " (" + std::string(path) + ")";
    msg += ": ";
    msg += detail ? detail : sqlite3_errstr(rc);
    return msg;
}

}  // namespace

Database::Database(const std::string& path, Mode mode) : path_(path) {
    int flags = SQLITE_OPEN_NOMUTEX;
    switch (mode) {
        case Mode::read_write_create:
            flags |= SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE;
            break;
        case Mode::read_write:
            flags |= SQLITE_OPEN_READWRITE;
            break;
        case Mode::read_only:
        case Mode::read_only_immutable:
            flags |= SQLITE_OPEN_READONLY;
            break;
    }
    std::string name = path;
    if (mode == Mode::read_only_immutable) {
        // A URI filename: '%', '?' and '#' of the path are escaped (sqlite.org/uri.html).
        name = "file:";
        for (const char c : path) {
            if (c == '%' || c == '?' || c == '#') {
                static constexpr char kHex[] = "0123456789ABCDEF";
                const auto u = static_cast<unsigned char>(c);
                name += '%';
                name += kHex[u >> 4];
                name += kHex[u & 15];
            } else {
                name += c;
            }
        }
        name += "?immutable=1";
        flags |= SQLITE_OPEN_URI;
    }
    const int rc = sqlite3_open_v2(name.c_str(), &db_, flags, nullptr);
    if (rc != SQLITE_OK) {
        const std::string msg = describe(rc, "cannot open database", path, db_ ? sqlite3_errmsg(db_) : nullptr);
        sqlite3_close_v2(db_);
        db_ = nullptr;
        throw StorageError(kind_of(rc), msg, rc);
    }
    sqlite3_extended_result_codes(db_, 1);
}

Database::~Database() {
    if (db_) sqlite3_close_v2(db_);
}

Database::Database(Database&& other) noexcept : db_(std::exchange(other.db_, nullptr)), path_(std::move(other.path_)) {}

Database& Database::operator=(Database&& other) noexcept {
    if (this != &other) {
        if (db_) sqlite3_close_v2(db_);
        db_ = std::exchange(other.db_, nullptr);
        path_ = std::move(other.path_);
    }
    return *this;
}

void Database::fail(int rc, std::string_view what) const {
    throw StorageError(kind_of(rc), describe(rc, what, path_, db_ ? sqlite3_errmsg(db_) : nullptr), rc);
}

void Database::exec(std::string_view sql) {
    const std::string text(sql);
    char* err = nullptr;
    const int rc = sqlite3_exec(db_, text.c_str(), nullptr, nullptr, &err);
    if (rc != SQLITE_OK) {
        std::string detail = err ? err : sqlite3_errstr(rc);
        sqlite3_free(err);
        throw StorageError(kind_of(rc), describe(rc, "cannot run SQL", path_, detail.c_str()), rc);
    }
}

Statement Database::prepare(std::string_view sql) {
    return Statement(*this, sql);
}

std::int64_t Database::query_int(std::string_view sql) {
    Statement st(*this, sql);
    if (!st.step()) return 0;
    return st.column_int(0);
}

std::string Database::query_text(std::string_view sql) {
    Statement st(*this, sql);
    if (!st.step()) return {};
    return st.column_text(0);
}

std::int64_t Database::last_insert_rowid() const {
    return sqlite3_last_insert_rowid(db_);
}

int Database::changes() const {
    return sqlite3_changes(db_);
}

void Database::set_busy_timeout(int milliseconds) {
    sqlite3_busy_timeout(db_, milliseconds);
}

Statement::Statement(Database& db, std::string_view sql) : db_(&db) {
    const int rc = sqlite3_prepare_v3(db.handle(), sql.data(), static_cast<int>(sql.size()), SQLITE_PREPARE_PERSISTENT,
                                      &stmt_, nullptr);
    if (rc != SQLITE_OK) db.fail(rc, "cannot prepare \"" + std::string(sql.substr(0, 60)) + "\"");
}

Statement::~Statement() {
    if (stmt_) sqlite3_finalize(stmt_);
}

Statement::Statement(Statement&& other) noexcept
    : db_(std::exchange(other.db_, nullptr)), stmt_(std::exchange(other.stmt_, nullptr)) {}

Statement& Statement::operator=(Statement&& other) noexcept {
    if (this != &other) {
        if (stmt_) sqlite3_finalize(stmt_);
        db_ = std::exchange(other.db_, nullptr);
        stmt_ = std::exchange(other.stmt_, nullptr);
    }
    return *this;
}

Statement& Statement::bind(int index, std::int64_t value) {
    const int rc = sqlite3_bind_int64(stmt_, index, value);
    if (rc != SQLITE_OK) db_->fail(rc, "cannot bind");
    return *this;
}

Statement& Statement::bind(int index, double value) {
    const int rc = sqlite3_bind_double(stmt_, index, value);
    if (rc != SQLITE_OK) db_->fail(rc, "cannot bind");
    return *this;
}

Statement& Statement::bind(int index, std::string_view text) {
    // A null data() would bind SQL NULL; an empty string_view means the empty text.
    const char* data = text.data() ? text.data() : "";
    const int rc = sqlite3_bind_text64(stmt_, index, data, text.size(), SQLITE_TRANSIENT, SQLITE_UTF8);
    if (rc != SQLITE_OK) db_->fail(rc, "cannot bind");
    return *this;
}

Statement& Statement::bind_null(int index) {
    const int rc = sqlite3_bind_null(stmt_, index);
    if (rc != SQLITE_OK) db_->fail(rc, "cannot bind");
    return *this;
}

bool Statement::step() {
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    sqlite3_reset(stmt_);
    db_->fail(rc, "statement failed");
}

void Statement::run() {
    step();
    reset();
}

void Statement::reset() {
    sqlite3_reset(stmt_);
}

void Statement::clear_bindings() {
    sqlite3_clear_bindings(stmt_);
}

bool Statement::is_null(int column) const {
    return sqlite3_column_type(stmt_, column) == SQLITE_NULL;
}

std::int64_t Statement::column_int(int column) const {
    return sqlite3_column_int64(stmt_, column);
}

double Statement::column_double(int column) const {
    return sqlite3_column_double(stmt_, column);
}

std::string Statement::column_text(int column) const {
    const auto* text = sqlite3_column_text(stmt_, column);
    if (!text) return {};
    return std::string(reinterpret_cast<const char*>(text),
                       static_cast<std::size_t>(sqlite3_column_bytes(stmt_, column)));
}

std::optional<std::int64_t> Statement::column_opt_int(int column) const {
    if (is_null(column)) return std::nullopt;
    return column_int(column);
}

std::optional<double> Statement::column_opt_double(int column) const {
    if (is_null(column)) return std::nullopt;
    return column_double(column);
}

std::optional<std::string> Statement::column_opt_text(int column) const {
    if (is_null(column)) return std::nullopt;
    return column_text(column);
}

Transaction::Transaction(Database& db, bool immediate) : db_(db) {
    nested_ = !sqlite3_get_autocommit(db_.handle());
    if (nested_) {
        db_.exec("SAVEPOINT ballbar_nested");
    } else {
        db_.exec(immediate ? "BEGIN IMMEDIATE" : "BEGIN");
    }
    open_ = true;
}

Transaction::~Transaction() {
    if (!open_ || sqlite3_get_autocommit(db_.handle())) return;  // committed, or SQLite rolled back itself
    if (nested_) {
        sqlite3_exec(db_.handle(), "ROLLBACK TO ballbar_nested; RELEASE ballbar_nested", nullptr, nullptr, nullptr);
    } else {
        sqlite3_exec(db_.handle(), "ROLLBACK", nullptr, nullptr, nullptr);
    }
}

void Transaction::commit() {
    db_.exec(nested_ ? "RELEASE ballbar_nested" : "COMMIT");
    open_ = false;
}

}  // namespace ballbar::storage
