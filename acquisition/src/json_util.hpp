// SPDX-License-Identifier: MIT
// Small checked accessors for the machine and plan files (internal).
#pragma once

#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "ballbar/acquisition/machine_file.hpp"
#include "ballbar/analysis/limits.hpp"
#include "ballbar/fileio/json_fields.hpp"

namespace ballbar::acquisition::detail {

inline nlohmann::json parse_json(std::string_view text, const std::string& what) {
    try {
        return nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) {  // parse_error, and out_of_range for a number past double
        throw PlanError(what + ": not valid JSON (" + e.what() + ")");
    }
}

inline double get_number(const nlohmann::json& j, const std::string& key, const std::string& what) {
    if (!j.contains(key)) throw PlanError(what + ": missing key \"" + key + "\"");
    if (!j.at(key).is_number()) throw PlanError(what + ": \"" + key + "\" must be a number");
    return j.at(key).get<double>();
}

/// Refuses a key of `j` not in `allowed`: a typo silently ignored would run a procedure the operator
/// did not ask for. `what` names the file and the object ("machine file", "plan file: capture").
inline void only_keys(const nlohmann::json& j, const std::string& what,
                      std::initializer_list<std::string_view> allowed) {
    const auto refuse = [](const std::string& where, const std::string& problem) {
        throw PlanError(where + ": " + problem);
    };
    fileio::JsonFields<nlohmann::json, decltype(refuse)>(j, what, refuse).only_known(allowed);
}

/// `value` finite and in [lo, hi], or PlanError naming the field ("plan file: dwell_s = 1e+308 is outside ...").
inline double require_in(const std::string& what, const std::string& key, double value, double lo, double hi,
                         std::string_view unit) {
    if (const std::string why = analysis::limits::check_in(value, lo, hi, unit); !why.empty())
        throw PlanError(what + ": " + key + " " + why);
    return value;
}

/// `value` finite, > lo and <= hi.
inline double require_above(const std::string& what, const std::string& key, double value, double lo, double hi,
                            std::string_view unit) {
    if (const std::string why = analysis::limits::check_above(value, lo, hi, unit); !why.empty())
        throw PlanError(what + ": " + key + " " + why);
    return value;
}

/// A position vector: every component within ±limits::kPosition_mm.
inline analysis::Vec3 require_position(const std::string& what, const std::string& key, const analysis::Vec3& v) {
    static constexpr const char* kAxes[] = {"[0]", "[1]", "[2]"};
    for (int i = 0; i < 3; ++i)
        require_in(what, key + kAxes[i], v[i], -analysis::limits::kPosition_mm, analysis::limits::kPosition_mm, "mm");
    return v;
}

inline std::string get_string(const nlohmann::json& j, const std::string& key, const std::string& what) {
    if (!j.contains(key)) throw PlanError(what + ": missing key \"" + key + "\"");
    if (!j.at(key).is_string()) throw PlanError(what + ": \"" + key + "\" must be a string");
    return j.at(key).get<std::string>();
}

inline analysis::Vec3 to_vec3(const nlohmann::json& v, const std::string& key, const std::string& what) {
    if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
        throw PlanError(what + ": \"" + key + "\" must be an array of three numbers (mm)");
    return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
}

inline analysis::Vec3 get_vec3(const nlohmann::json& j, const std::string& key, const std::string& what,
                               const analysis::Vec3& fallback) {
    if (!j.contains(key)) return fallback;
    return to_vec3(j.at(key), key, what);
}

/// A "tolerances" object: a machine file's (`circular`: circularity_um allowed too) or a plan test's
/// (`what` "plan file: tests[1]"). Each value > 0 and below a bound that catches mm typed for µm.
/// PlanError naming the key.
Tolerances parse_tolerances(const nlohmann::json& t, const std::string& what, bool circular);
/// The same object back (only the values given).
nlohmann::json tolerances_json(const Tolerances& tolerances);

}  // namespace ballbar::acquisition::detail
