// SPDX-License-Identifier: MIT
#include "ballbar/storage/imports.hpp"

#include <nettle/sha2.h>

#include <array>
#include <cstdint>

#include "ballbar/storage/sqlite.hpp"

namespace ballbar::storage {
namespace {

ImportRecord import_record(Statement& st) {
    ImportRecord r;
    r.session_id = st.column_int(0);
    r.content_sha256 = st.column_text(1);
    r.file_name = st.column_text(2);
    r.bytes = st.column_int(3);
    r.imported_at = st.column_text(4);
    return r;
}

}  // namespace

Sha256::Sha256() {
    sha256_init(&ctx_);
}

void Sha256::update(std::string_view bytes) {
    sha256_update(&ctx_, bytes.size(), reinterpret_cast<const std::uint8_t*>(bytes.data()));
}

std::string Sha256::hex() {
    std::array<std::uint8_t, SHA256_DIGEST_SIZE> digest{};
    sha256_digest(&ctx_, digest.size(), digest.data());  // also resets the context
    static constexpr char kHex[] = "0123456789abcdef";
    std::string out;
    out.reserve(2 * digest.size());
    for (std::uint8_t b : digest) {
        out += kHex[b >> 4];
        out += kHex[b & 0xf];
    }
    return out;
}

std::string sha256_hex(std::string_view bytes) {
    Sha256 h;
    h.update(bytes);
    return h.hex();
}

void record_import(Store& store, std::int64_t session_id, std::string_view content_sha256, std::string_view file_name,
                   std::int64_t bytes) {
    store.session(session_id);  // Kind::not_found for no such session
    auto st = store.db().prepare(
        "INSERT INTO imports(session_id, content_sha256, file_name, bytes, imported_at) VALUES (?,?,?,?,?)");
    st.bind(1, session_id).bind(2, content_sha256).bind(3, file_name).bind(4, bytes).bind(5, store.now_iso8601());
    st.run();
}

std::vector<ImportRecord> imports_of_content(Store& store, std::string_view content_sha256) {
    std::vector<ImportRecord> out;
    if (store.schema_version() < 5) return out;
    auto st = store.db().prepare(
        "SELECT session_id, content_sha256, file_name, bytes, imported_at FROM imports WHERE content_sha256 = ? "
        "ORDER BY session_id");
    st.bind(1, content_sha256);
    while (st.step()) out.push_back(import_record(st));
    return out;
}

std::optional<ImportRecord> import_of(Store& store, std::int64_t session_id) {
    if (store.schema_version() < 5) return std::nullopt;
    auto st = store.db().prepare(
        "SELECT session_id, content_sha256, file_name, bytes, imported_at FROM imports WHERE session_id = ?");
    st.bind(1, session_id);
    if (!st.step()) return std::nullopt;
    return import_record(st);
}

}  // namespace ballbar::storage
