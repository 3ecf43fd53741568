// SPDX-License-Identifier: MIT
#include "ballbar/storage/machine_json.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "ballbar/analysis/limits.hpp"
#include "ballbar/fileio/json_fields.hpp"

namespace ballbar::storage {
namespace {

using analysis::MachineType;
using ojson = nlohmann::ordered_json;  // keeps the key order of what we read and write

bool uses(MachineType type, std::string_view key) {
    if (key == "tool_ball_mm") return true;
    if (key == "a_pivot_mm") return type == MachineType::TTTRR || type == MachineType::RTTTR;
    if (key == "c_offset_mm") return type == MachineType::TTTRR;
    return false;
}

constexpr std::string_view kGeometryKeys[] = {"tool_ball_mm", "a_pivot_mm", "c_offset_mm"};

analysis::Vec3 vec_from(const ojson& j, std::string_view key) {
    const std::string where = "machine." + std::string(key);
    if (!j.is_array() || j.size() != 3) throw FormatError(where + " must be an array of 3 numbers (mm)");
    analysis::Vec3 v;
    for (int i = 0; i < 3; ++i) {
        const auto& e = j[static_cast<std::size_t>(i)];
        if (!e.is_number()) throw FormatError(where + " must be an array of 3 numbers (mm)");
        v[i] = e.get<double>();
        if (const std::string why =
                analysis::limits::check_in(v[i], -analysis::limits::kPosition_mm, analysis::limits::kPosition_mm, "mm");
            !why.empty())
            throw FormatError(where + "[" + std::to_string(i) + "] " + why);
    }
    return v;
}

ojson parse_object(std::string_view text, std::string_view what) {
    ojson j;
    try {
        j = ojson::parse(text);
    } catch (const ojson::exception& e) {  // parse_error, and out_of_range for a number past double
        throw FormatError(std::string(what) + " is not valid JSON: " + e.what());
    }
    if (!j.is_object()) throw FormatError(std::string(what) + " must be a JSON object");
    return j;
}

}  // namespace

std::string machine_to_json(const analysis::MachineGeometry& m) {
    nlohmann::ordered_json j = nlohmann::ordered_json::object();
    j["type"] = std::string(analysis::to_string(m.type));
    if (!m.name.empty()) j["name"] = m.name;
    if (uses(m.type, "a_pivot_mm")) j["a_pivot_mm"] = fileio::vec3_json<nlohmann::ordered_json>(m.a_pivot_mm);
    if (uses(m.type, "c_offset_mm")) j["c_offset_mm"] = fileio::vec3_json<nlohmann::ordered_json>(m.c_offset_mm);
    j["tool_ball_mm"] = fileio::vec3_json<nlohmann::ordered_json>(m.tool_ball_mm);
    return j.dump();  // nlohmann writes doubles with the shortest round-tripping representation
}

analysis::MachineGeometry machine_from_json(std::string_view text, std::vector<std::string>* warnings) {
    const ojson j = parse_object(text, "machine");
    analysis::MachineGeometry m;
    const auto type_it = j.find("type");
    if (type_it == j.end()) throw FormatError("machine has no \"type\" (RRTTT, TTTRR or RTTTR)");
    if (!type_it->is_string()) throw FormatError("machine.type must be a string: RRTTT, TTTRR or RTTTR");
    const auto type = analysis::parse_machine_type(type_it->get<std::string>());
    if (!type) throw FormatError("machine.type \"" + type_it->get<std::string>() + "\" is not RRTTT, TTTRR or RTTTR");
    m.type = *type;
    if (const auto it = j.find("name"); it != j.end()) {
        if (!it->is_string()) throw FormatError("machine.name must be a string");
        m.name = it->get<std::string>();
    }
    for (const auto key : kGeometryKeys) {
        const auto it = j.find(std::string(key));
        if (!uses(m.type, key)) continue;
        if (it == j.end()) {
            throw FormatError("machine of type " + std::string(analysis::to_string(m.type)) + " needs \"" +
                              std::string(key) + "\"");
        }
        const analysis::Vec3 v = vec_from(*it, key);
        if (key == "tool_ball_mm") m.tool_ball_mm = v;
        if (key == "a_pivot_mm") m.a_pivot_mm = v;
        if (key == "c_offset_mm") m.c_offset_mm = v;
    }
    if (warnings) {
        for (const auto& [key, value] : j.items()) {
            if (key == "type" || key == "name") continue;
            const bool geometry = key == "tool_ball_mm" || key == "a_pivot_mm" || key == "c_offset_mm";
            if (geometry && uses(m.type, key)) continue;
            warnings->push_back("machine key \"" + key + "\" is " +
                                (geometry ? "not used by a " + std::string(analysis::to_string(m.type)) + " machine"
                                          : std::string("unknown")) +
                                "; ignored");
        }
    }
    return m;
}

std::string instrument_to_json(const Instrument& in) {
    nlohmann::ordered_json j = nlohmann::ordered_json::object();
    if (!in.model.empty()) j["model"] = in.model;
    if (!in.serial.empty()) j["serial"] = in.serial;
    if (!in.firmware.empty()) j["firmware"] = in.firmware;
    if (in.calibrated_length_mm) j["calibrated_length_mm"] = *in.calibrated_length_mm;
    if (!in.calibration_date.empty()) j["calibration_date"] = in.calibration_date;
    if (!in.extra_json.empty()) {
        const auto extra = nlohmann::ordered_json::parse(in.extra_json, nullptr, false);
        if (extra.is_object()) {
            for (const auto& [key, value] : extra.items()) {
                if (!j.contains(key)) j[key] = value;
            }
        }
    }
    return j.dump();
}

Instrument instrument_from_json(std::string_view text) {
    ojson j = parse_object(text, "instrument");
    Instrument in;
    auto take_string = [&](const char* key, std::string& out) {
        const auto it = j.find(key);
        if (it == j.end()) return;
        if (!it->is_string()) throw FormatError(std::string("instrument.") + key + " must be a string");
        out = it->get<std::string>();
        j.erase(it);
    };
    take_string("model", in.model);
    take_string("serial", in.serial);
    take_string("firmware", in.firmware);
    take_string("calibration_date", in.calibration_date);
    if (const auto it = j.find("calibrated_length_mm"); it != j.end()) {
        if (!it->is_number() || !(it->get<double>() > 0) || !std::isfinite(it->get<double>())) {
            throw FormatError("instrument.calibrated_length_mm must be a positive number (mm)");
        }
        if (const std::string why =
                analysis::limits::check_above(it->get<double>(), 0, analysis::limits::kLength_mm, "mm");
            !why.empty())
            throw FormatError("instrument.calibrated_length_mm " + why);
        in.calibrated_length_mm = it->get<double>();
        j.erase(it);
    }
    if (!j.empty()) in.extra_json = j.dump();
    return in;
}

}  // namespace ballbar::storage
