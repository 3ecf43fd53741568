// SPDX-License-Identifier: MIT
#include "ballbar/fleet/pg.hpp"

#include <libpq-fe.h>

#include <charconv>
#include <memory>

namespace ballbar::fleet::pg {
namespace {

/// libpq's message without its trailing newline, on one line.
std::string one_line(const char* message) {
    std::string s = message ? message : "";
    while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
    for (char& ch : s)
        if (ch == '\n') ch = ' ';
    return s;
}

/// Refuses a connection string that holds a password, or one libpq cannot parse.
void check_conninfo(const std::string& conninfo) {
    char* error = nullptr;
    PQconninfoOption* options = PQconninfoParse(conninfo.c_str(), &error);
    if (!options) {
        const std::string why = one_line(error);
        PQfreemem(error);
        throw FleetError(FleetError::Kind::bad_conninfo, "the connection string cannot be used: " + why);
    }
    bool has_password = false;
    for (const PQconninfoOption* o = options; o->keyword; ++o)
        if (std::string_view(o->keyword) == "password" && o->val && *o->val) has_password = true;
    PQconninfoFree(options);
    if (has_password)
        throw FleetError(FleetError::Kind::bad_conninfo,
                         "the connection string holds a password: give it in PGPASSWORD or ~/.pgpass instead "
                         "(a command line is seen by every user of the machine and kept in the shell's history)");
}

}  // namespace

Result::~Result() {
    if (r_) PQclear(r_);
}

Result& Result::operator=(Result&& o) noexcept {
    if (this != &o) {
        if (r_) PQclear(r_);
        r_ = o.r_;
        o.r_ = nullptr;
    }
    return *this;
}

int Result::rows() const {
    return r_ ? PQntuples(r_) : 0;
}

bool Result::is_null(int row, int col) const {
    return PQgetisnull(r_, row, col) != 0;
}

std::string Result::text(int row, int col) const {
    return std::string(PQgetvalue(r_, row, col), static_cast<std::size_t>(PQgetlength(r_, row, col)));
}

std::optional<std::string> Result::opt_text(int row, int col) const {
    if (is_null(row, col)) return std::nullopt;
    return text(row, col);
}

std::int64_t Result::integer(int row, int col) const {
    const std::string s = text(row, col);
    std::int64_t v = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || end != s.data() + s.size())
        throw FleetError(FleetError::Kind::server, "the server answered '" + s + "' where a number was expected");
    return v;
}

std::int64_t Result::affected() const {
    const char* n = r_ ? PQcmdTuples(r_) : "";
    std::int64_t v = 0;
    std::from_chars(n, n + std::char_traits<char>::length(n), v);
    return v;
}

Connection::Connection(const std::string& conninfo) : c_(nullptr) {
    check_conninfo(conninfo);
    // Never a hang, whatever the link does: a server that does not answer is given up after 10 s, and a
    // link that dies mid-sync (no reset ever arrives) is found by TCP keepalives and the user timeout
    // within about half a minute. The connection string's own settings (and PG* variables) come after
    // and win over these defaults.
    const char* keys[] = {"connect_timeout",           "keepalives",       "keepalives_idle",
                          "keepalives_interval",       "keepalives_count", "tcp_user_timeout",
                          "fallback_application_name", "dbname",           nullptr};
    const char* values[] = {"10", "1", "10", "5", "3", "30000", "ballbar", conninfo.c_str(), nullptr};
    c_ = PQconnectdbParams(keys, values, /*expand_dbname=*/1);
    if (!c_) throw FleetError(FleetError::Kind::connect, "cannot connect to the PostgreSQL server: out of memory");
    if (PQstatus(c_) != CONNECTION_OK) {
        const std::string why = one_line(PQerrorMessage(c_));
        PQfinish(c_);
        c_ = nullptr;
        throw FleetError(FleetError::Kind::connect, "cannot connect to the PostgreSQL server: " + why);
    }
    // Notices (e.g. "schema already exists, skipping") are not the user's concern.
    PQsetNoticeProcessor(
        c_, [](void*, const char*) {}, nullptr);
}

Connection::~Connection() {
    if (c_) PQfinish(c_);
}

void Connection::fail(std::string_view what, pg_result* r) {
    std::string why = one_line(r ? PQresultErrorMessage(r) : PQerrorMessage(c_));
    if (why.empty()) why = one_line(PQerrorMessage(c_));
    if (r) PQclear(r);
    const bool link = PQstatus(c_) != CONNECTION_OK;
    throw FleetError(link ? FleetError::Kind::link : FleetError::Kind::server,
                     (link ? "the connection to the PostgreSQL server broke during " : "the server refused ") +
                         std::string(what) + ": " + why);
}

namespace {
std::string first_words(std::string_view sql) {
    const auto start = sql.find_first_not_of(" \n");
    if (start == std::string_view::npos) return "a statement";
    sql.remove_prefix(start);
    const auto end = sql.find_first_of("(\n;");
    return std::string(sql.substr(0, std::min<std::size_t>(end, 60)));
}
}  // namespace

Result Connection::exec(std::string_view sql) {
    pg_result* r = PQexec(c_, std::string(sql).c_str());
    const auto status = r ? PQresultStatus(r) : PGRES_FATAL_ERROR;
    if (status != PGRES_COMMAND_OK && status != PGRES_TUPLES_OK) fail(first_words(sql), r);
    return Result(r);
}

Result Connection::exec_params(std::string_view sql, const std::vector<Param>& params) {
    std::vector<const char*> values;
    values.reserve(params.size());
    for (const auto& p : params) values.push_back(p ? p->c_str() : nullptr);
    pg_result* r = PQexecParams(c_, std::string(sql).c_str(), static_cast<int>(values.size()), nullptr, values.data(),
                                nullptr, nullptr, 0);
    const auto status = r ? PQresultStatus(r) : PGRES_FATAL_ERROR;
    if (status != PGRES_COMMAND_OK && status != PGRES_TUPLES_OK) fail(first_words(sql), r);
    return Result(r);
}

void Connection::begin_copy(std::string_view copy_sql) {
    pg_result* r = PQexec(c_, std::string(copy_sql).c_str());
    if (!r || PQresultStatus(r) != PGRES_COPY_IN) fail(first_words(copy_sql), r);
    PQclear(r);
}

void Connection::put_copy(std::string_view data) {
    // libpq buffers what the socket does not take at once and sends it as it can (blocking connection).
    constexpr std::size_t kPiece = 1 << 20;
    for (std::size_t at = 0; at < data.size(); at += kPiece) {
        const auto n = std::min(kPiece, data.size() - at);
        if (PQputCopyData(c_, data.data() + at, static_cast<int>(n)) != 1) fail("COPY");
    }
}

std::int64_t Connection::end_copy() {
    if (PQputCopyEnd(c_, nullptr) != 1) fail("COPY");
    std::int64_t copied = 0;
    pg_result* failure = nullptr;
    while (pg_result* res = PQgetResult(c_)) {
        if (PQresultStatus(res) == PGRES_COMMAND_OK) {
            copied += Result(res).affected();
        } else {
            if (failure) PQclear(failure);
            failure = res;
        }
    }
    if (failure) fail("COPY", failure);
    return copied;
}

std::int64_t Connection::copy_in(std::string_view copy_sql, std::string_view data) {
    begin_copy(copy_sql);
    put_copy(data);
    return end_copy();
}

int Connection::server_version() const {
    return PQserverVersion(c_);
}

std::string Connection::where() const {
    const char* host = PQhost(c_);
    const char* port = PQport(c_);
    const char* db = PQdb(c_);
    return std::string("database ") + (db ? db : "?") + " on " + (host ? host : "?") + ":" + (port ? port : "?");
}

Transaction::Transaction(Connection& c) : c_(c) {
    c_.exec("BEGIN");
}

Transaction::~Transaction() {
    if (!done_) {
        try {
            c_.exec("ROLLBACK");
        } catch (...) {  // a broken link rolls back on the server by itself
        }
    }
}

void Transaction::commit() {
    c_.exec("COMMIT");
    done_ = true;
}

void append_copy_text(std::string& out, std::string_view text) {
    for (char ch : text) {
        switch (ch) {
            case '\\':
                out += "\\\\";
                break;
            case '\t':
                out += "\\t";
                break;
            case '\n':
                out += "\\n";
                break;
            case '\r':
                out += "\\r";
                break;
            default:
                out += ch;
        }
    }
}

}  // namespace ballbar::fleet::pg
