// SPDX-License-Identifier: MIT
#include "ballbar/storage/model_codec.hpp"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "ballbar/analysis/limits.hpp"
#include "ballbar/analysis/rounding.hpp"
#include "ballbar/fileio/json_fields.hpp"
#include "ballbar/storage/machine_json.hpp"

namespace ballbar::storage {
namespace {

using ojson = nlohmann::ordered_json;  // "format" first, then the keys in the order written

constexpr std::string_view kKeys[] = {"format",       "machine",   "params",          "std",
                                      "unobservable", "sockets",   "residual_rms_um", "readings",
                                      "converged",    "empirical", "added",           "measured_poses"};

constexpr const char* kPoseKeys[] = {"X_mm", "Y_mm", "Z_mm", "A_deg", "B_deg", "C_deg"};

std::string known_keys() {
    std::string out;
    for (std::string_view k : kKeys) out += (out.empty() ? "" : ", ") + std::string(k);
    return out;
}

[[noreturn]] void refuse(const std::string& key, const std::string& problem) {
    throw FormatError(key + ": " + problem);
}
using ModelFields = fileio::JsonFields<ojson, decltype(&refuse)>;  // fileio/json_fields.hpp

analysis::Vec3 vec3_field(const ModelFields& f, const ojson& v, const std::string& where) {
    if (!v.is_array() || v.size() != 3) f.refuse(where, "must be an array of 3 numbers (mm)");
    analysis::Vec3 out;
    for (std::size_t i = 0; i < 3; ++i)
        out[static_cast<int>(i)] = f.number_value(v[i], where + "[" + std::to_string(i) + "]");
    return out;
}

analysis::Param param_from(const std::string& name, const std::string& where) {
    const auto p = analysis::parse_param(name);
    if (!p) throw FormatError(where + ": unknown parameter");
    return *p;
}

const ojson& object_at(const ojson& j, const char* key, const char* shape) {
    const ojson& v = j.at(key);
    if (!v.is_object()) throw FormatError(std::string("\"") + key + "\" must be an object " + shape);
    return v;
}

}  // namespace

analysis::ErrorParams ErrorModel::values() const {
    analysis::ErrorParams out{};
    for (const ModelParam& p : params) out[p.param] = p.value;
    return out;
}

std::string model_to_json(const ErrorModel& m) {
    ojson j = ojson::object();
    j["format"] = std::string(kModelFormat);
    j["machine"] = ojson::parse(machine_to_json(m.machine));
    j["params"] = ojson::object();
    for (const ModelParam& p : m.params) j["params"][std::string(analysis::param_info(p.param).name)] = p.value;
    // std, unobservable and sockets are written even when empty: a script reads them without asking first.
    j["std"] = ojson::object();
    for (const ModelParam& p : m.params)
        if (p.std) j["std"][std::string(analysis::param_info(p.param).name)] = *p.std;
    j["unobservable"] = ojson::array();
    for (analysis::Param p : m.unobservable) j["unobservable"].push_back(std::string(analysis::param_info(p).name));
    if (!m.empirical.empty()) {
        j["empirical"] = ojson::object();
        for (const analysis::LearnedTerm& t : m.empirical) j["empirical"][t.term.name()] = t.value;
    }
    j["sockets"] = ojson::array();
    for (const ModelSocket& s : m.sockets)
        j["sockets"].push_back({{"nominal_mm", fileio::vec3_json<nlohmann::ordered_json>(s.nominal_mm)},
                                {"offset_mm", fileio::vec3_json<nlohmann::ordered_json>(s.offset_mm)}});
    if (m.residual_rms_um) j["residual_rms_um"] = *m.residual_rms_um;
    if (m.readings) j["readings"] = *m.readings;
    if (m.converged) j["converged"] = *m.converged;
    if (!m.added.empty()) j["added"] = m.added;
    if (m.measured_poses && !m.measured_poses->empty) {
        ojson r = ojson::object();
        for (int i = 0; i < analysis::PoseRange::kAxes; ++i) {
            const auto k = static_cast<std::size_t>(i);
            // Angles in degrees as the plan gave them (30, not 30.000000000000004), to 1e-9°.
            auto out = [i](double v) { return i < 3 ? v : analysis::decimal_round(analysis::rad_to_deg(v), 9); };
            r[kPoseKeys[k]] = ojson::array({out(m.measured_poses->min[k]), out(m.measured_poses->max[k])});
        }
        j["measured_poses"] = r;
    }
    return j.dump();
}

ErrorModel model_from_json(std::string_view text) {
    ojson j;
    try {
        j = ojson::parse(text);
    } catch (const ojson::exception& e) {  // parse_error, and out_of_range for a number past double
        throw FormatError(std::string("malformed JSON: ") + e.what());
    }
    if (!j.is_object()) throw FormatError("a model must be a JSON object");
    const ModelFields f(j, "", &refuse);
    for (const auto& item : j.items())
        if (std::find(std::begin(kKeys), std::end(kKeys), item.key()) == std::end(kKeys))
            throw FormatError(item.key() + ": unknown key (" + known_keys() + ")");
    if (j.contains("format") && j["format"] != kModelFormat)
        throw FormatError("format " + j["format"].dump() + " is not " + std::string(kModelFormat));
    if (!j.contains("machine")) throw FormatError("no \"machine\" (the geometry is needed)");
    ErrorModel m;
    try {
        m.machine = machine_from_json(j["machine"].dump());
    } catch (const FormatError& e) {
        // machine_from_json names its keys "machine.…" already
        const std::string what = e.what();
        throw FormatError(what.starts_with("machine") ? what : "machine: " + what);
    }
    if (!j.contains("params") || !j["params"].is_object())
        throw FormatError("\"params\" must be an object {\"X0C\": value, ...}");
    for (const auto& item : j["params"].items()) {
        const std::string where = "params." + item.key();
        const analysis::Param p = param_from(item.key(), where);
        const double v = f.number_value(item.value(), where);
        if (const std::string why = analysis::limits::check_param(p, v); !why.empty())
            throw FormatError(where + " " + why);
        m.params.push_back({p, v, std::nullopt});
    }
    if (j.contains("std"))
        for (const auto& item : object_at(j, "std", "{\"X0C\": uncertainty, ...}").items()) {
            const std::string where = "std." + item.key();
            const analysis::Param p = param_from(item.key(), where);
            const double v = f.number_value(item.value(), where);
            if (v < 0) throw FormatError(where + ": an uncertainty cannot be negative");
            const auto it =
                std::find_if(m.params.begin(), m.params.end(), [p](const ModelParam& q) { return q.param == p; });
            if (it == m.params.end()) throw FormatError(where + ": the model holds no value of " + item.key());
            it->std = v;
        }
    if (j.contains("unobservable")) {
        if (!j["unobservable"].is_array()) throw FormatError("\"unobservable\" must be an array of parameter names");
        for (const auto& v : j["unobservable"]) {
            if (!v.is_string()) throw FormatError("\"unobservable\" must be an array of parameter names");
            m.unobservable.push_back(param_from(v.get<std::string>(), "unobservable." + v.get<std::string>()));
        }
    }
    if (j.contains("empirical"))  // terms learned by `discover`: angular error tables, positioning errors
        for (const auto& item : object_at(j, "empirical", "{\"C_angular_h1_cos\": value, ...}").items()) {
            const std::string where = "empirical." + item.key();
            const auto t = analysis::parse_empirical_term(item.key());
            if (!t) throw FormatError(where + ": unknown term");
            m.empirical.push_back({*t, f.number_value(item.value(), where), 0.0});
        }
    if (j.contains("sockets")) {
        if (!j["sockets"].is_array()) throw FormatError("\"sockets\" must be an array");
        for (std::size_t i = 0; i < j["sockets"].size(); ++i) {
            const ojson& s = j["sockets"][i];
            const std::string where = "sockets[" + std::to_string(i) + "]";
            if (!s.is_object() || !s.contains("nominal_mm") || !s.contains("offset_mm") || s.size() != 2)
                throw FormatError(where + ": must be {\"nominal_mm\": [x, y, z], \"offset_mm\": [x, y, z]}");
            m.sockets.push_back({vec3_field(f, s["nominal_mm"], where + ".nominal_mm"),
                                 vec3_field(f, s["offset_mm"], where + ".offset_mm")});
        }
    }
    if (f.has("residual_rms_um")) {
        m.residual_rms_um = f.number("residual_rms_um");
        if (*m.residual_rms_um < 0) f.refuse("residual_rms_um", "cannot be negative");
    }
    if (f.has("readings")) m.readings = static_cast<int>(f.count("readings", 2147483647));
    if (f.has("converged")) m.converged = f.boolean("converged");
    if (f.has("added")) m.added = f.text("added");
    if (f.has("measured_poses")) {
        const ojson& r = j["measured_poses"];
        if (!r.is_object() || r.size() != 6)
            throw FormatError("measured_poses: must be {\"X_mm\": [min, max], ... \"C_deg\": [min, max]}");
        analysis::PoseRange range;
        range.empty = false;
        for (int i = 0; i < analysis::PoseRange::kAxes; ++i) {
            const auto k = static_cast<std::size_t>(i);
            const std::string key = kPoseKeys[k];
            const std::string where = "measured_poses." + key;
            if (!r.contains(key)) throw FormatError(where + ": missing");
            const ojson& v = r[key];
            if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number() ||
                !std::isfinite(v[0].get<double>()) || !std::isfinite(v[1].get<double>()) || v[0] > v[1])
                throw FormatError(where + ": must be [min, max], finite, min <= max");
            const double scale = i < 3 ? 1.0 : analysis::deg_to_rad(1.0);
            range.min[k] = v[0].get<double>() * scale;
            range.max[k] = v[1].get<double>() * scale;
        }
        m.measured_poses = range;
    }
    return m;
}

}  // namespace ballbar::storage
