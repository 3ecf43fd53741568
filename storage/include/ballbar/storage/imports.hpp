// SPDX-License-Identifier: MIT
// Where an imported session came from: the SHA-256 of the imported file's bytes, its name and size
// (table `imports`, schema v5), so that importing the same content again is recognised (`ballbar
// import` refuses it and names the session it duplicates; docs/storage.md).
#pragma once

#include <nettle/sha2.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/storage/store.hpp"

namespace ballbar::storage {

/// SHA-256 (FIPS 180-4, computed by libnettle) fed in pieces, so a file can be hashed while it is
/// streamed.
class Sha256 {
  public:
    Sha256();
    void update(std::string_view bytes);
    /// The digest of everything fed so far as 64 lower-case hex digits; starts a new hash.
    std::string hex();

  private:
    sha256_ctx ctx_;
};

/// SHA-256 of `bytes` as 64 lower-case hex digits.
std::string sha256_hex(std::string_view bytes);

struct ImportRecord {
    std::int64_t session_id = 0;
    std::string content_sha256;  ///< of the file's bytes, 64 hex digits
    std::string file_name;       ///< as given on the command line
    std::int64_t bytes = 0;
    std::string imported_at;  ///< ISO 8601 UTC
};

/// Records the file a session was imported from (in the caller's transaction, if any). Throws
/// StorageError (Kind::not_found for no such session).
void record_import(Store& store, std::int64_t session_id, std::string_view content_sha256, std::string_view file_name,
                   std::int64_t bytes);

/// The sessions imported from files with this content, oldest first (sessions imported before schema
/// v5 recorded no hash and are not found).
std::vector<ImportRecord> imports_of_content(Store& store, std::string_view content_sha256);

/// The file a session was imported from, if it was recorded. Empty for a database opened read-only
/// below schema v5.
std::optional<ImportRecord> import_of(Store& store, std::int64_t session_id);

}  // namespace ballbar::storage
