// SPDX-License-Identifier: MIT
// The content hash of imported files (SHA-256, FIPS 180-4's own examples and the padding's edge cases
// checked against coreutils' sha256sum) and the imports table that finds a file imported before.
#include <gtest/gtest.h>

#include <string>

#include "ballbar/storage/imports.hpp"
#include "ballbar/storage/store.hpp"
#include "test_util.hpp"

namespace ballbar::storage {
namespace {

using test::TempDir;

TEST(ContentHash, Fips180ExamplesAndOneMillionAs) {
    EXPECT_EQ(sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
    EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    EXPECT_EQ(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
              "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
    EXPECT_EQ(sha256_hex(std::string(1000000, 'a')),
              "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(ContentHash, PaddingEdgesMatchSha256sum) {
    // 55 bytes: the length still fits the block; 56 and 63: it takes a second block; 64: a full block.
    EXPECT_EQ(sha256_hex(std::string(55, 'x')), "d5e285683cd4efc02d021a5c62014694958901005d6f71e89e0989fac77e4072");
    EXPECT_EQ(sha256_hex(std::string(56, 'x')), "04c26261370ee7541549d16dee320c723e3fd14671e66a099afe0a377c16888e");
    EXPECT_EQ(sha256_hex(std::string(63, 'x')), "75220b47218278e656f2013bb8f0c455a25eaf01e86c64924e9d48d89776d6f2");
    EXPECT_EQ(sha256_hex(std::string(64, 'x')), "7ce100971f64e7001e8fe5a51973ecdfe1ced42befe7ee8d5fd6219506b5393c");
    EXPECT_NE(sha256_hex("a\n"), sha256_hex("a\r\n")) << "the bytes, not the text";
}

TEST(Imports, TheSameContentIsFoundWithItsSessionsAndFile) {
    TempDir dir;
    Store store(dir.file("imports.db"));
    NewSession ns;
    ns.machine.type = analysis::MachineType::TTTRR;
    ns.source = SessionSource::imported;
    const auto a = store.create_session(ns);
    const auto b = store.create_session(ns);
    const std::string h = sha256_hex("file content");
    EXPECT_TRUE(imports_of_content(store, h).empty());
    record_import(store, a, h, "first.readings", 12);
    record_import(store, b, h, "copy.readings", 12);
    const auto found = imports_of_content(store, h);
    ASSERT_EQ(found.size(), 2u);
    EXPECT_EQ(found[0].session_id, a);
    EXPECT_EQ(found[0].file_name, "first.readings");
    EXPECT_EQ(found[1].session_id, b);
    EXPECT_EQ(found[0].bytes, 12);
    EXPECT_FALSE(found[0].imported_at.empty());
    EXPECT_TRUE(imports_of_content(store, sha256_hex("other content")).empty());
    ASSERT_TRUE(import_of(store, b));
    EXPECT_EQ(import_of(store, b)->file_name, "copy.readings");
    EXPECT_THROW(record_import(store, 99, h, "x", 1), StorageError) << "no such session";
    EXPECT_THROW(record_import(store, a, h, "again", 12), StorageError) << "one file per session";
}

}  // namespace
}  // namespace ballbar::storage
