// SPDX-License-Identifier: MIT
// Small checked accessors for the machine and plan files (internal).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "ballbar/acquisition/machine_file.hpp"

namespace ballbar::acquisition::detail {

inline nlohmann::json parse_json(std::string_view text, const std::string& what) {
    try {
        return nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error& e) {
        throw PlanError(what + ": not valid JSON (" + e.what() + ")");
    }
}

inline double get_number(const nlohmann::json& j, const std::string& key, const std::string& what) {
    if (!j.contains(key)) throw PlanError(what + ": missing key \"" + key + "\"");
    if (!j.at(key).is_number()) throw PlanError(what + ": \"" + key + "\" must be a number");
    return j.at(key).get<double>();
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

}  // namespace ballbar::acquisition::detail
