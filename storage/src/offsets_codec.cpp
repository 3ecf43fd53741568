// SPDX-License-Identifier: MIT
#include "ballbar/storage/offsets_codec.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>

#include "ballbar/analysis/limits.hpp"
#include "ballbar/fileio/json_fields.hpp"
#include "ballbar/storage/machine_json.hpp"

namespace ballbar::storage {

namespace ba = ballbar::analysis;
using nlohmann::json;

ba::NcOffsetTable offsets_from_json(std::string_view text) {
    json j;
    try {
        j = json::parse(text);
    } catch (const json::exception& e) {  // parse_error, and out_of_range for a number past double
        throw FormatError(std::string("malformed JSON: ") + e.what());
    }
    if (!j.is_object()) throw FormatError("the table must be a JSON object");
    // Positions and lengths within ±100 m, rotary offsets within ±36000° (docs/compensation.md).
    auto number = [&](const json& v, const std::string& field) {
        if (!v.is_number()) throw FormatError(field + ": must be a number");
        const bool deg = field.size() > 4 && field.compare(field.size() - 4, 4, "_deg") == 0;
        const double lim = deg ? ba::limits::kRotary_deg : ba::limits::kPosition_mm;
        if (const std::string why = ba::limits::check_in(v.get<double>(), -lim, lim, deg ? "deg" : "mm"); !why.empty())
            throw FormatError(field + " " + why);
        return v.get<double>();
    };
    const auto refuse = [](const std::string& where, const std::string& problem) {
        throw FormatError(where.empty() ? problem : where + ": " + problem);
    };
    using Fields = fileio::JsonFields<json, decltype(refuse)>;
    Fields(j, "", refuse).only_known({"format", "work_offsets", "tools", "measured_tool_length_mm"});
    ba::NcOffsetTable t;
    for (const auto& item : j.items()) {
        const std::string& key = item.key();
        if (key == "format") {
            if (item.value() != std::string(kOffsetsFormat))
                throw FormatError("format " + item.value().dump() + " is not " + std::string(kOffsetsFormat));
        } else if (key == "measured_tool_length_mm") {
            t.measured_tool_length_mm = number(item.value(), key);
        } else if (key == "work_offsets") {
            if (!item.value().is_object()) throw FormatError("work_offsets must be an object");
            for (const auto& w : item.value().items()) {
                static const char* names[] = {"G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3"};
                if (std::find(std::begin(names), std::end(names), w.key()) == std::end(names))
                    throw FormatError("work_offsets." + w.key() + ": not G54–G59 or G59.1–G59.3");
                if (!w.value().is_object()) throw FormatError("work_offsets." + w.key() + " must be an object");
                Fields(w.value(), "work_offsets." + w.key(), refuse)
                    .only_known({"X_mm", "Y_mm", "Z_mm", "A_deg", "B_deg", "C_deg"});
                ba::Pose p;
                for (const auto& a : w.value().items()) {
                    const std::string f = "work_offsets." + w.key() + "." + a.key();
                    const double v = number(a.value(), f);
                    if (a.key() == "X_mm")
                        p.X_mm = v;
                    else if (a.key() == "Y_mm")
                        p.Y_mm = v;
                    else if (a.key() == "Z_mm")
                        p.Z_mm = v;
                    else if (a.key() == "A_deg")
                        p.A_rad = ba::deg_to_rad(v);
                    else if (a.key() == "B_deg")
                        p.B_rad = ba::deg_to_rad(v);
                    else  // C_deg: the keys are known
                        p.C_rad = ba::deg_to_rad(v);
                }
                t.work[w.key()] = p;
            }
        } else if (key == "tools") {
            if (!item.value().is_object()) throw FormatError("tools must be an object");
            for (const auto& tl : item.value().items()) {
                const std::string& k = tl.key();
                if (k.empty() || k.size() > 6 ||
                    !std::all_of(k.begin(), k.end(), [](char c) { return c >= '0' && c <= '9'; }))
                    throw FormatError("tools." + k + ": the key must be a tool number");
                if (!tl.value().is_object() || !tl.value().contains("length_mm") || tl.value().size() != 1)
                    throw FormatError("tools." + k + " must be {\"length_mm\": L}");
                t.tool_length_mm[std::stoi(k)] = number(tl.value()["length_mm"], "tools." + k + ".length_mm");
            }
        }
    }
    return t;
}

std::string offsets_to_json(const ba::NcOffsetTable& t) {
    nlohmann::ordered_json j;
    j["format"] = std::string(kOffsetsFormat);
    j["work_offsets"] = nlohmann::ordered_json::object();
    for (const auto& [name, p] : t.work)
        j["work_offsets"][name] = {{"X_mm", p.X_mm},
                                   {"Y_mm", p.Y_mm},
                                   {"Z_mm", p.Z_mm},
                                   {"A_deg", ba::rad_to_deg(p.A_rad)},
                                   {"B_deg", ba::rad_to_deg(p.B_rad)},
                                   {"C_deg", ba::rad_to_deg(p.C_rad)}};
    j["tools"] = nlohmann::ordered_json::object();
    for (const auto& [number, length] : t.tool_length_mm) j["tools"][std::to_string(number)] = {{"length_mm", length}};
    j["measured_tool_length_mm"] = t.measured_tool_length_mm;
    return j.dump();
}

}  // namespace ballbar::storage
