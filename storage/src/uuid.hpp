// SPDX-License-Identifier: MIT
// Identities that survive a fleet: random (version 4) UUIDs, 122 bits from the kernel's generator.
// Sessions, results, models, machines and the station itself carry one; two stations never hand out the
// same (a clash is 2^-61 likely after 2^30 of them), whatever seed their emulators ran with.
#pragma once

#include <sqlite3.h>
#include <sys/random.h>

#include <array>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <string>

#include "ballbar/storage/sqlite.hpp"

namespace ballbar::storage::detail {

inline std::string random_uuid() {
    std::array<std::uint8_t, 16> b{};
    for (std::size_t got = 0; got < b.size();) {
        const ssize_t n = ::getrandom(b.data() + got, b.size() - got, 0);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) throw StorageError(StorageError::Kind::sqlite, "no random numbers for a uuid (getrandom failed)");
        got += static_cast<std::size_t>(n);
    }
    b[6] = static_cast<std::uint8_t>((b[6] & 0x0f) | 0x40);  // version 4
    b[8] = static_cast<std::uint8_t>((b[8] & 0x3f) | 0x80);  // variant 10
    char s[37];
    std::snprintf(s, sizeof s, "%02x%02x%02x%02x-%02x%02x-%02x%02x-%02x%02x-%02x%02x%02x%02x%02x%02x", b[0], b[1], b[2],
                  b[3], b[4], b[5], b[6], b[7], b[8], b[9], b[10], b[11], b[12], b[13], b[14], b[15]);
    return s;
}

/// `ballbar_uuid()` in SQL on this connection: the migrations give rows of earlier versions their ids.
inline void register_uuid_function(sqlite3* db) {
    sqlite3_create_function(
        db, "ballbar_uuid", 0, SQLITE_UTF8, nullptr,
        [](sqlite3_context* ctx, int, sqlite3_value**) {
            try {
                const std::string u = random_uuid();
                sqlite3_result_text(ctx, u.c_str(), static_cast<int>(u.size()), SQLITE_TRANSIENT);
            } catch (const StorageError& e) {
                sqlite3_result_error(ctx, e.what(), -1);
            }
        },
        nullptr, nullptr);
}

}  // namespace ballbar::storage::detail
