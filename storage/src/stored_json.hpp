// SPDX-License-Identifier: MIT
// Reading a stored result that went through several shapes (the circular and discovery results): a key
// may be absent or null, both meaning absent; a key that is there must have its type. read_stored parses
// the payload and says which result a refused key belongs to (internal).
#pragma once

#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ballbar/storage/machine_json.hpp"

namespace ballbar::storage::detail {

/// `"key" what`; the reader prefixes the result's kind.
class StoredKeyError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

[[noreturn]] inline void bad_key(const std::string& key, const std::string& what) {
    throw StoredKeyError("\"" + key + "\" " + what);
}
/// A key's value; null is absent.
inline const nlohmann::json* find(const nlohmann::json& j, const char* key) {
    if (!j.is_object()) return nullptr;
    const auto it = j.find(key);
    return it == j.end() || it->is_null() ? nullptr : &*it;
}
/// `where` prefixes the key in the message ("runs[1].").
inline std::optional<double> opt_num(const nlohmann::json& j, const char* key, const std::string& where = {}) {
    const nlohmann::json* v = find(j, key);
    if (!v) return std::nullopt;
    if (!v->is_number()) bad_key(where + key, "must be a number");
    return v->get<double>();
}
inline double num(const nlohmann::json& j, const char* key, const std::string& where = {}) {
    const auto v = opt_num(j, key, where);
    if (!v) bad_key(where + key, "is missing");
    return *v;
}
/// Absent: "".
inline std::string str(const nlohmann::json& j, const char* key, const std::string& where = {}) {
    const nlohmann::json* v = find(j, key);
    if (!v) return {};
    if (!v->is_string()) bad_key(where + key, "must be a string");
    return v->get<std::string>();
}
/// An array of numbers; a null entry is NaN (an empty bin). Absent: empty.
inline std::vector<double> nums(const nlohmann::json& j, const char* key) {
    std::vector<double> out;
    const nlohmann::json* v = find(j, key);
    if (!v) return out;
    if (!v->is_array()) bad_key(key, "must be an array of numbers");
    for (const auto& x : *v) {
        if (x.is_null())
            out.push_back(std::nan(""));
        else if (x.is_number())
            out.push_back(x.get<double>());
        else
            bad_key(key, "must be an array of numbers");
    }
    return out;
}
/// The strings of a list (other entries skipped). Absent: empty.
inline std::vector<std::string> strings(const nlohmann::json* list) {
    std::vector<std::string> out;
    if (list && list->is_array())
        for (const auto& k : *list)
            if (k.is_string()) out.push_back(k.get<std::string>());
    return out;
}

/// `read(payload)` on the stored payload of a result of `kind`: FormatError when the text is not a JSON
/// object, and a key the reader refuses (StoredKeyError) said as `result "kind": "key" what`.
template <class Read>
auto read_stored(std::string_view text, const std::string& kind, Read read)
    -> decltype(read(std::declval<const nlohmann::json&>())) {
    nlohmann::json payload;
    try {
        payload = nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) {
        throw FormatError("result \"" + kind + "\" is not valid JSON: " + e.what());
    }
    if (!payload.is_object()) throw FormatError("result \"" + kind + "\" is not a JSON object");
    try {
        return read(payload);
    } catch (const StoredKeyError& e) {
        throw FormatError("result \"" + kind + "\": " + e.what());
    }
}

}  // namespace ballbar::storage::detail
