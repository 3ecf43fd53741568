// SPDX-License-Identifier: MIT
// Reading one diagnostic out of a circular result's JSON, for the tests of the commands that print it.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace ballbar::test {

/// The diagnostic `key` of a circular result's JSON (docs/cli.md: diagnostics are a list of
/// {key, unit, value, value_std, ...}); null when the list has none.
inline nlohmann::json diagnostic(const nlohmann::json& result, const std::string& key) {
    for (const auto& d : result.at("diagnostics"))
        if (d.at("key") == key) return d;
    return nullptr;
}

}  // namespace ballbar::test
