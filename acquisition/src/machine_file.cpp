// SPDX-License-Identifier: MIT
#include "ballbar/acquisition/machine_file.hpp"

#include <nlohmann/json.hpp>

#include "json_util.hpp"

namespace ballbar::acquisition {

using nlohmann::json;
using namespace ballbar::analysis;
namespace limits = ballbar::analysis::limits;

std::string_view axis_name(Axis a) {
    static constexpr std::array<std::string_view, kAxisCount> names = {"X", "Y", "Z", "A", "B", "C"};
    return names[static_cast<std::size_t>(a)];
}

namespace {

constexpr std::string_view kFormat = "ballbar-machine/1";

bool is_rotary(Axis a) {
    return a == Axis::A || a == Axis::B || a == Axis::C;
}

std::string travel_key(Axis a) {
    return std::string(axis_name(a)) + (is_rotary(a) ? "_deg" : "_mm");
}

}  // namespace

MachineFile parse_machine_file(std::string_view json_text) {
    const json j = detail::parse_json(json_text, "machine file");
    if (!j.is_object()) throw PlanError("machine file: expected a JSON object");
    detail::only_keys(j, "machine file",
                      {"format", "type", "name", "tool_ball_mm", "a_pivot_mm", "c_offset_mm", "dialect", "feed_mm_min",
                       "travel", "tolerances"});
    if (j.contains("format") && j.at("format") != kFormat)
        throw PlanError("machine file: format must be \"" + std::string(kFormat) + "\"");
    MachineFile m;
    const std::string type = detail::get_string(j, "type", "machine file");
    const auto t = parse_machine_type(type);
    if (!t) throw PlanError("machine file: type \"" + type + "\" is not RRTTT, TTTRR or RTTTR");
    m.geometry.type = *t;
    if (j.contains("name")) m.geometry.name = detail::get_string(j, "name", "machine file");
    for (auto [key, into] :
         {std::pair{"tool_ball_mm", &m.geometry.tool_ball_mm}, std::pair{"a_pivot_mm", &m.geometry.a_pivot_mm},
          std::pair{"c_offset_mm", &m.geometry.c_offset_mm}})
        *into = detail::require_position("machine file", key, detail::get_vec3(j, key, "machine file", Vec3::Zero()));
    if (j.contains("dialect")) {
        const std::string d = detail::get_string(j, "dialect", "machine file");
        const auto dialect = parse_nc_dialect(d);
        if (!dialect) throw PlanError("machine file: dialect \"" + d + "\" is not fanuc or linuxcnc");
        m.dialect = *dialect;
    }
    if (j.contains("feed_mm_min")) {
        m.feed_mm_min =
            detail::require_in("machine file", "feed_mm_min", detail::get_number(j, "feed_mm_min", "machine file"),
                               limits::kFeedMin_mm_min, limits::kFeedMax_mm_min, "mm/min");
    }
    if (j.contains("travel")) {
        const json& tr = j.at("travel");
        if (!tr.is_object()) throw PlanError("machine file: travel must be an object of [min, max] pairs");
        for (auto it = tr.begin(); it != tr.end(); ++it) {
            bool known = false;
            for (int i = 0; i < kAxisCount; ++i) {
                const auto a = static_cast<Axis>(i);
                if (it.key() != travel_key(a)) continue;
                known = true;
                const json& v = it.value();
                if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number() || v[0] > v[1])
                    throw PlanError("machine file: travel." + it.key() + " must be [min, max] with min <= max");
                const double lim = is_rotary(a) ? limits::kRotary_deg : limits::kPosition_mm;
                for (int k = 0; k < 2; ++k)
                    detail::require_in("machine file", "travel." + it.key() + (k == 0 ? "[0]" : "[1]"),
                                       v[static_cast<std::size_t>(k)].get<double>(), -lim, lim,
                                       is_rotary(a) ? "deg" : "mm");
                const double scale = is_rotary(a) ? deg_to_rad(1.0) : 1.0;
                m.travel[static_cast<std::size_t>(i)] = {v[0].get<double>() * scale, v[1].get<double>() * scale};
            }
            if (!known)
                throw PlanError("machine file: unknown travel key \"" + it.key() +
                                "\" (X_mm, Y_mm, Z_mm, A_deg, B_deg, C_deg)");
        }
    }
    if (j.contains("tolerances")) m.tolerances = detail::parse_tolerances(j.at("tolerances"), "machine file", true);
    return m;
}

std::string write_machine_file(const MachineFile& m) {
    json j;
    j["format"] = kFormat;
    j["type"] = std::string(to_string(m.geometry.type));
    if (!m.geometry.name.empty()) j["name"] = m.geometry.name;
    auto arr = [](const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); };
    j["tool_ball_mm"] = arr(m.geometry.tool_ball_mm);
    j["a_pivot_mm"] = arr(m.geometry.a_pivot_mm);
    j["c_offset_mm"] = arr(m.geometry.c_offset_mm);
    j["dialect"] = std::string(to_string(m.dialect));
    j["feed_mm_min"] = m.feed_mm_min;
    json tr = json::object();
    for (int i = 0; i < kAxisCount; ++i) {
        const auto a = static_cast<Axis>(i);
        const AxisRange& r = m.range(a);
        if (r.min <= -1e9 && r.max >= 1e9) continue;
        const double scale = is_rotary(a) ? rad_to_deg(1.0) : 1.0;
        tr[travel_key(a)] = json::array({r.min * scale, r.max * scale});
    }
    j["travel"] = tr;
    if (m.tolerances.any()) j["tolerances"] = detail::tolerances_json(m.tolerances);
    return j.dump(2) + "\n";
}

}  // namespace ballbar::acquisition

namespace ballbar::acquisition {

MachineFile seed_machine(MachineType type) {
    MachineFile m;
    m.geometry.type = type;
    switch (type) {
        case MachineType::RRTTT:
            m.geometry.name = "seed RRTTT (P1 Table 1)";
            m.geometry.tool_ball_mm = Vec3(0, 0, -250);
            break;
        case MachineType::TTTRR:
            m.geometry.name = "seed TTTRR (P1 Table 2)";
            m.geometry.c_offset_mm = Vec3(0, 0, -100);
            break;
        case MachineType::RTTTR:
            m.geometry.name = "seed RTTTR";
            m.geometry.tool_ball_mm = Vec3(0, 0, -150);
            m.geometry.a_pivot_mm = Vec3(0, 0, -200);
            break;
    }
    m.travel = {AxisRange{-800, 800}, AxisRange{-800, 800}, AxisRange{-800, 800},
                AxisRange{-2.1, 2.1}, AxisRange{-2.1, 2.1}, AxisRange{-2 * kPi, 2 * kPi}};
    m.feed_mm_min = 2000;
    return m;
}

}  // namespace ballbar::acquisition

namespace ballbar::acquisition::detail {

namespace {
/// The largest tolerance taken: beyond it a value is a typo (mm for µm), not a shop's limit.
constexpr double kMaxLocation_um = 10000, kMaxAngle_arcsec = 36000, kMaxCircularity_um = 10000;
}  // namespace

Tolerances parse_tolerances(const nlohmann::json& t, const std::string& what, bool circular) {
    if (!t.is_object()) throw PlanError(what + ": tolerances must be an object");
    if (circular)
        only_keys(t, what + ": tolerances", {"location_um", "angle_arcsec", "circularity_um"});
    else
        only_keys(t, what + ": tolerances", {"location_um", "angle_arcsec"});
    Tolerances out;
    auto take = [&](const char* key, double max, const char* unit) -> std::optional<double> {
        if (!t.contains(key)) return std::nullopt;
        return require_above(what, std::string("tolerances.") + key, get_number(t, key, what + ": tolerances"), 0, max,
                             unit);
    };
    out.location_um = take("location_um", kMaxLocation_um, "µm");
    out.angle_arcsec = take("angle_arcsec", kMaxAngle_arcsec, "arcsec");
    if (circular) out.circularity_um = take("circularity_um", kMaxCircularity_um, "µm");
    return out;
}

nlohmann::json tolerances_json(const Tolerances& tolerances) {
    nlohmann::json t = nlohmann::json::object();
    if (tolerances.location_um) t["location_um"] = *tolerances.location_um;
    if (tolerances.angle_arcsec) t["angle_arcsec"] = *tolerances.angle_arcsec;
    if (tolerances.circularity_um) t["circularity_um"] = *tolerances.circularity_um;
    return t;
}

}  // namespace ballbar::acquisition::detail
