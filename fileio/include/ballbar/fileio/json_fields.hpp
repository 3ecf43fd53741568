// SPDX-License-Identifier: MIT
// The helper of the strict readers of JSON documents: each field is checked for its type and range, an
// unknown key is refused, and every error names the key. The stored model, the procedure's results,
// identify's and compensate's results and the `solve` requests read through it; the trace header, the
// emulator configuration and the machine and plan files refuse their unknown keys through it
// (only_known) and keep their own few type checks. A reader
// gives its own `fail`, which throws its own error type with its own prefix; the checks are these.
// Works on any nlohmann::basic_json (json, ordered_json).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <initializer_list>
#include <string>
#include <string_view>

namespace ballbar::fileio {

/// How a reader refuses: throws its own error for `key` (a path: "params.X0C", "estimates[2].std") and
/// `problem` ("must be a finite number"). Must not return.
template <class Fail>
concept JsonFail = requires(Fail f, const std::string& key, const std::string& problem) {
    f(key, problem);
};

template <class Json, JsonFail Fail>
class JsonFields {
  public:
    /// The object at `where` ("" for the document); `fail` refuses. A value that is not an object is
    /// refused at once.
    JsonFields(const Json& object, std::string where, Fail refuse_with)
        : j_(object), where_(std::move(where)), fail_(std::move(refuse_with)) {
        if (!j_.is_object()) refuse("", "must be a JSON object");
    }

    /// Refuses a key that is not one of `keys`, naming it and, with `list`, the keys there are.
    void only(std::initializer_list<std::string_view> keys, bool list = false) const {
        for (const auto& item : j_.items()) {
            if (std::find(keys.begin(), keys.end(), item.key()) != keys.end()) continue;
            std::string known;
            if (list)
                for (std::string_view k : keys) known.append(known.empty() ? " (known: " : ", ").append(k);
            refuse(item.key(), "is not a key it has" + (list ? known + ")" : ""));
        }
    }
    /// Refuses a key that is not one of `keys`, blaming the object itself (its path, "" for the
    /// document): `unknown key "speed" (known: direction, start_deg, …)`. The form the trace header, the
    /// machine, plan and emulator files and the offsets table use.
    void only_known(std::initializer_list<std::string_view> keys) const {
        for (const auto& item : j_.items()) {
            if (std::find(keys.begin(), keys.end(), item.key()) != keys.end()) continue;
            std::string known;
            for (std::string_view k : keys) known.append(known.empty() ? "" : ", ").append(k);
            fail_(where_, "unknown key \"" + item.key() + "\" (known: " + known + ")");
            std::abort();  // unreachable: a fail throws
        }
    }
    bool has(const char* key) const { return j_.contains(key); }
    /// The value of an optional key: nullptr when it is absent or null.
    const Json* optional(const char* key) const {
        const auto it = j_.find(key);
        return it == j_.end() || it->is_null() ? nullptr : &*it;
    }
    /// The value of a key that must be there.
    const Json& at(const char* key) const {
        const auto it = j_.find(key);
        if (it == j_.end()) refuse(key, "is missing");
        return *it;
    }
    [[noreturn]] void refuse(const std::string& key, const std::string& problem) const {
        fail_(where_.empty() ? key : key.empty() ? where_ : where_ + "." + key, problem);
        std::abort();  // unreachable: a fail throws
    }
    std::string path(const std::string& key) const { return where_.empty() ? key : where_ + "." + key; }
    const Fail& fail() const { return fail_; }

    double number(const char* key) const { return number_value(at(key), key); }
    double number_value(const Json& v, const std::string& key) const {
        if (!v.is_number() || !std::isfinite(v.template get<double>())) refuse(key, "must be a finite number");
        return v.template get<double>();
    }
    /// A count: a non-negative integer up to `max`.
    std::int64_t count(const char* key, std::int64_t max = 2'000'000'000) const {
        const Json& v = at(key);
        if (!v.is_number_integer() || v.template get<std::int64_t>() < 0 || v.template get<std::int64_t>() > max)
            refuse(key, "must be a non-negative integer");
        return v.template get<std::int64_t>();
    }
    bool boolean(const char* key) const {
        const Json& v = at(key);
        if (!v.is_boolean()) refuse(key, "must be true or false");
        return v.template get<bool>();
    }
    std::string text(const char* key) const {
        const Json& v = at(key);
        if (!v.is_string()) refuse(key, "must be a string");
        return v.template get<std::string>();
    }
    /// [x, y, z]: three finite numbers.
    template <class Vec>
    Vec vec3(const char* key) const {
        const Json& v = at(key);
        if (!v.is_array() || v.size() != 3) refuse(key, "must be an array of three numbers");
        return Vec(number_value(v[0], key), number_value(v[1], key), number_value(v[2], key));
    }

  private:
    const Json& j_;
    std::string where_;
    Fail fail_;
};

/// [x, y, z] of a vector (Eigen's or anything with x(), y(), z()): the writers' side of vec3.
template <class Json, class Vec>
Json vec3_json(const Vec& v) {
    return Json::array({v.x(), v.y(), v.z()});
}

}  // namespace ballbar::fileio
