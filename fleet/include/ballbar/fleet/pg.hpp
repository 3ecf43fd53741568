// SPDX-License-Identifier: MIT
// A thin RAII layer over libpq: a connection, results, parameterised statements and COPY FROM STDIN.
// Every failure throws FleetError with what the server or the link said.
//
//   pg::Connection c("host=db.plant user=station7 dbname=ballbar");   // password: PGPASSWORD or ~/.pgpass
//   c.exec("BEGIN");
//   auto r = c.exec_params("SELECT samples_next_seq FROM ballbar.sessions WHERE uuid = $1", {uuid});
//   c.copy_in("COPY ballbar.samples FROM STDIN", text_rows);
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

struct pg_conn;
struct pg_result;

namespace ballbar::fleet {

/// What went wrong with the server: the categories a user can act on.
class FleetError : public std::runtime_error {
  public:
    enum class Kind {
        bad_conninfo,  ///< the connection string cannot be used (malformed, or holds a password)
        connect,       ///< the server cannot be reached, refuses the role or its password
        link,          ///< the connection broke or the server ended it mid-sync (committed chunks stay)
        server,        ///< the server refused a statement (permission, constraint, …)
        newer_schema,  ///< the server's ballbar schema is newer than this ballbar
    };
    FleetError(Kind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
    Kind kind() const { return kind_; }

  private:
    Kind kind_;
};

namespace pg {

/// A query's result. Move-only.
class Result {
  public:
    explicit Result(pg_result* r = nullptr) : r_(r) {}
    ~Result();
    Result(Result&& o) noexcept : r_(o.r_) { o.r_ = nullptr; }
    Result& operator=(Result&& o) noexcept;
    Result(const Result&) = delete;
    Result& operator=(const Result&) = delete;

    int rows() const;
    bool is_null(int row, int col) const;
    std::string text(int row, int col) const;
    std::optional<std::string> opt_text(int row, int col) const;
    std::int64_t integer(int row, int col) const;
    /// Rows an INSERT/UPDATE/COPY changed (PQcmdTuples).
    std::int64_t affected() const;

  private:
    pg_result* r_;
};

/// A parameter of exec_params: text, or SQL NULL.
using Param = std::optional<std::string>;

/// One connection. Move-only; closes on destruction.
class Connection {
  public:
    /// Connects with a libpq connection string or URI. A password in it is refused (Kind::bad_conninfo):
    /// it would sit in the shell's history and the process list; libpq takes it from PGPASSWORD or
    /// ~/.pgpass. Throws Kind::connect when the server cannot be reached or refuses the login.
    explicit Connection(const std::string& conninfo);
    ~Connection();
    Connection(Connection&& o) noexcept : c_(o.c_) { o.c_ = nullptr; }
    Connection& operator=(Connection&&) = delete;
    Connection(const Connection&) = delete;
    Connection& operator=(const Connection&) = delete;

    /// Runs one or more statements without parameters.
    Result exec(std::string_view sql);
    /// Runs one statement with $1, $2, … as text parameters.
    Result exec_params(std::string_view sql, const std::vector<Param>& params);
    /// COPY … FROM STDIN with `data` in COPY's text format (rows ending in '\n'); returns the rows copied.
    std::int64_t copy_in(std::string_view copy_sql, std::string_view data);
    /// The same in pieces, so the server parses one while the next is made: begin_copy, put_copy as
    /// often as there are rows (each piece whole rows), end_copy (the rows copied).
    void begin_copy(std::string_view copy_sql);
    void put_copy(std::string_view data);
    std::int64_t end_copy();
    /// The server's version number (e.g. 150018) and where it is, for messages.
    int server_version() const;
    std::string where() const;

  private:
    [[noreturn]] void fail(std::string_view what, pg_result* r = nullptr);
    pg_conn* c_;
};

/// A transaction: BEGIN on construction, ROLLBACK on destruction unless committed.
class Transaction {
  public:
    explicit Transaction(Connection& c);
    ~Transaction();
    Transaction(const Transaction&) = delete;
    Transaction& operator=(const Transaction&) = delete;
    void commit();

  private:
    Connection& c_;
    bool done_ = false;
};

/// `text` escaped for a field of COPY's text format (backslash, tab, newline, carriage return).
void append_copy_text(std::string& out, std::string_view text);

}  // namespace pg
}  // namespace ballbar::fleet
