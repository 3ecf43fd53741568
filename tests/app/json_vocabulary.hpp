// SPDX-License-Identifier: MIT
// The rules of docs/cli.md's "JSON output: one vocabulary", as a check any test can run on what a
// command printed. Written from the documented rules alone, not from the code that writes the JSON: it
// walks the document and names each violation with its key path.
#pragma once

#include <algorithm>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace ballbar::test {

namespace vocabulary_detail {

inline bool is_ascii(const std::string& s) {
    return std::all_of(s.begin(), s.end(), [](char c) { return static_cast<unsigned char>(c) < 0x80; });
}

inline std::vector<std::string> tokens(const std::string& key) {
    std::vector<std::string> out;
    std::string cur;
    for (char c : key) {
        if (c == '_') {
            out.push_back(cur);
            cur.clear();
        } else {
            cur += c;
        }
    }
    out.push_back(cur);
    return out;
}

/// A number, null, or an array/object of only numbers and nulls: a quantity, as opposed to a flag or a
/// text.
inline bool is_quantity(const nlohmann::json& v) {
    if (v.is_number() || v.is_null()) return true;
    if (v.is_array() || v.is_object()) {
        if (v.empty()) return false;
        for (const auto& e : v)
            if (!e.is_number() && !e.is_null()) return false;
        return true;
    }
    return false;
}

/// The units a `unit` value may name: the key suffixes of docs/cli.md, spelled the same.
inline const std::set<std::string>& units() {
    static const std::set<std::string> u = {
        "mm",  "um",       "rad",       "deg",      "arcsec",   "s",     "ms",        "us",      "hz", "C",
        "ppm", "um_per_m", "mm_per_mm", "um_per_h", "mm_per_h", "per_K", "ppm_per_K", "percent", "1"};
    return u;
}

/// Keys whose number is a count: an integer.
inline bool is_count_key(const std::string& k) {
    static const std::set<std::string> counts = {"samples", "points",     "readings",    "attempts",
                                                 "gaps",    "programs",   "pauses",      "iterations",
                                                 "blocks",  "n",          "dof",         "runs",
                                                 "errors",  "timeouts",   "locations",   "compensated",
                                                 "arcs",    "arc_chords", "void_dwells", "degrees_of_freedom",
                                                 "rank",    "tests",      "lines",       "retries"};
    if (counts.count(k)) return true;
    for (const char* suffix :
         {"_count", "_frames", "_samples", "_points", "_blocks", "_drops", "_dwells", "_readings", "_mismatches"})
        if (k.size() > std::string(suffix).size() && k.ends_with(suffix)) return true;
    return false;
}

/// A document in one of ballbar's versioned formats, embedded in an output (the model file under
/// identify's `model`): docs/cli.md keeps it as its format defines it.
inline bool is_embedded_document(const nlohmann::json& v) {
    return v.is_object() && v.contains("format") && v["format"].is_string() &&
           v["format"].get<std::string>().starts_with("ballbar-");
}

inline void walk(const nlohmann::json& j, const std::string& path, std::vector<std::string>& out) {
    static const std::regex key_re("^[A-Za-z][A-Za-z0-9_]*$");
    static const std::regex iso_re(R"(^\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}(\.\d+)?(Z|[+-]\d{2}:\d{2})$)");
    if (j.is_string()) {
        if (j.get<std::string>().empty()) out.push_back(path + ": \"\" (a missing value is null)");
        return;
    }
    if (j.is_array()) {
        for (std::size_t i = 0; i < j.size(); ++i) walk(j[i], path + "[" + std::to_string(i) + "]", out);
        return;
    }
    if (!j.is_object()) return;
    for (auto it = j.begin(); it != j.end(); ++it) {
        const std::string& k = it.key();
        const nlohmann::json& v = it.value();
        const std::string p = path.empty() ? k : path + "." + k;
        if (!std::regex_match(k, key_re)) out.push_back(p + ": key is not ASCII letters, digits and _");
        // The uncertainty: K_std next to K, and no other spelling.
        const auto t = tokens(k);
        const bool names_spread = std::any_of(t.begin(), t.end(), [](const std::string& s) {
            return s == "std" || s == "stderr" || s == "uncertainty" || s == "uncertainties";
        });
        if (names_spread && is_quantity(v)) {
            const bool suffix_form = k.size() > 4 && k.ends_with("_std") &&
                                     std::count(t.begin(), t.end(), std::string("std")) == 1 &&
                                     std::none_of(t.begin(), t.end(), [](const std::string& s) {
                                         return s == "stderr" || s == "uncertainty" || s == "uncertainties";
                                     });
            if (!suffix_form)
                out.push_back(p + ": an uncertainty is K_std next to K (not std, stderr, uncertainty, std_…)");
            else if (!j.contains(k.substr(0, k.size() - 4)))
                out.push_back(p + ": no " + k.substr(0, k.size() - 4) + " next to it");
        }
        if ((k == "unit" || k.ends_with("_unit")) && v.is_string() && !units().count(v.get<std::string>()))
            out.push_back(p + ": unit \"" + (is_ascii(v.get<std::string>()) ? v.get<std::string>() : "non-ASCII") +
                          "\" is not one of docs/cli.md's");
        if (is_count_key(k) && v.is_number() && !v.is_number_integer()) out.push_back(p + ": a count is an integer");
        if (k.ends_with("_at") && !v.is_null() && !(v.is_string() && std::regex_match(v.get<std::string>(), iso_re)))
            out.push_back(p + ": a time is ISO 8601 with its offset");
        if (k == "diagnostics") {
            if (!v.is_array()) {
                out.push_back(p + ": diagnostics are a list of objects");
            } else {
                for (std::size_t i = 0; i < v.size(); ++i) {
                    const auto& d = v[i];
                    for (const char* field : {"key", "unit", "value", "value_std"})
                        if (!d.is_object() || !d.contains(field))
                            out.push_back(p + "[" + std::to_string(i) + "]: a diagnostic has " + field);
                }
            }
        }
        // Embedded versioned documents, and the stored records an export carries as they were stored
        // (docs/cli.md), are not the output's own vocabulary.
        if (is_embedded_document(v) || k == "payload" || k == "params") continue;
        walk(v, p, out);
    }
}

}  // namespace vocabulary_detail

/// Every place `j` breaks docs/cli.md's vocabulary, as "key.path: what"; empty when it follows it.
inline std::vector<std::string> vocabulary_violations(const nlohmann::json& j) {
    std::vector<std::string> out;
    vocabulary_detail::walk(j, "", out);
    return out;
}

/// The same for every line of a JSON-lines output (events), each line a document.
inline std::vector<std::string> vocabulary_violations_of_lines(const std::string& text) {
    std::vector<std::string> out;
    std::size_t start = 0, line = 1;
    while (start < text.size()) {
        std::size_t end = text.find('\n', start);
        if (end == std::string::npos) end = text.size();
        const std::string l = text.substr(start, end - start);
        if (!l.empty()) {
            const auto j = nlohmann::json::parse(l, nullptr, false);
            if (j.is_discarded()) {
                out.push_back("line " + std::to_string(line) + ": not JSON: " + l.substr(0, 60));
            } else {
                for (const auto& v : vocabulary_violations(j)) out.push_back("line " + std::to_string(line) + ": " + v);
            }
        }
        start = end + 1;
        ++line;
    }
    return out;
}

}  // namespace ballbar::test
