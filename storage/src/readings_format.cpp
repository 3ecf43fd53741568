// SPDX-License-Identifier: MIT
// Writing `ballbar-readings/1` with shortest round-tripping numbers.
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>

#include "ballbar/analysis/kinematics.hpp"
#include "ballbar/fileio/output.hpp"
#include "ballbar/storage/machine_json.hpp"
#include "ballbar/storage/readings_file.hpp"
#include "shortest.hpp"

namespace ballbar::storage {
namespace {

using detail::shortest;

/// The shortest decimal degrees that read back (through deg_to_rad) to exactly `rad`: -30, not
/// -29.999999999999996. Falls back to the nearest double when no decimal maps back exactly.
std::string degrees(double rad) {
    const double d = analysis::rad_to_deg(rad);
    for (int precision = 1; precision <= 17; ++precision) {
        char buf[40];
        const auto r = std::to_chars(buf, buf + sizeof buf, d, std::chars_format::general, precision);
        double back = 0;
        std::from_chars(buf, r.ptr, back);
        if (analysis::deg_to_rad(back) == rad) return shortest(back);
    }
    double up = d, down = d;
    for (int k = 0; k < 16; ++k) {
        up = std::nextafter(up, std::numeric_limits<double>::infinity());
        if (analysis::deg_to_rad(up) == rad) return shortest(up);
        down = std::nextafter(down, -std::numeric_limits<double>::infinity());
        if (analysis::deg_to_rad(down) == rad) return shortest(down);
    }
    return shortest(d);
}

double rotary(const analysis::Pose& pose, char axis) {
    return axis == 'A' ? pose.A_rad : axis == 'B' ? pose.B_rad : pose.C_rad;
}

struct Column {
    std::string name;
    std::function<std::string(const analysis::Reading&)> value;  // "" = not given
};

std::string number_or_empty(const std::optional<double>& v) {
    return v ? shortest(*v) : std::string();
}

}  // namespace

std::string format_readings(const analysis::ReadingSet& set, const ReadingsMetadata& meta) {
    using nlohmann::json;
    std::string out = "# ballbar-readings/1\n";
    out += "# machine: " + machine_to_json(set.machine) + "\n";
    if (meta.instrument) out += "# instrument: " + instrument_to_json(*meta.instrument) + "\n";
    if (!meta.operator_name.empty()) out += "# operator: " + json(meta.operator_name).dump() + "\n";
    if (!meta.started_at.empty()) out += "# started_at: " + json(meta.started_at).dump() + "\n";
    if (!meta.notes.empty()) out += "# notes: " + json(meta.notes).dump() + "\n";
    for (const auto& [key, value] : meta.extra) out += "# " + key + ": " + value + "\n";

    const auto rot = analysis::rotary_axes(set.machine.type);
    const auto& machine = set.machine;
    std::vector<Column> all = {
        {"time_s", [](const auto& r) { return r.time_s != 0 ? shortest(r.time_s) : std::string(); }},
        {"location", [](const auto& r) { return r.location >= 0 ? std::to_string(r.location) : std::string(); }},
        {"point", [](const auto& r) { return r.point >= 0 ? std::to_string(r.point) : std::string(); }},
        {"step", [](const auto& r) { return r.step > 0 ? std::to_string(r.step) : std::string(); }},
        {"X_mm", [](const auto& r) { return shortest(r.pose.X_mm); }},
        {"Y_mm", [](const auto& r) { return shortest(r.pose.Y_mm); }},
        {"Z_mm", [](const auto& r) { return shortest(r.pose.Z_mm); }},
        {std::string(1, rot.first) + "_deg", [a = rot.first](const auto& r) { return degrees(rotary(r.pose, a)); }},
        {std::string(1, rot.second) + "_deg", [a = rot.second](const auto& r) { return degrees(rotary(r.pose, a)); }},
        {"socket_x_mm", [](const auto& r) { return shortest(r.socket_mm.x()); }},
        {"socket_y_mm", [](const auto& r) { return shortest(r.socket_mm.y()); }},
        {"socket_z_mm", [](const auto& r) { return shortest(r.socket_mm.z()); }},
        {"measured_mm", [](const auto& r) { return shortest(r.measured_mm); }},
        {"nominal_mm",
         [&machine](const auto& r) { return shortest(analysis::nominal_length(machine, r.pose, r.socket_mm)); }},
        {"n", [](const auto& r) { return r.n > 0 ? std::to_string(r.n) : std::string(); }},
        {"std_mm", [](const auto& r) { return number_or_empty(r.std_mm); }},
        {"bar_temp_C", [](const auto& r) { return number_or_empty(r.bar_temp_C); }},
        {"air_temp_C", [](const auto& r) { return number_or_empty(r.air_temp_C); }},
        {"machine_temp_C", [](const auto& r) { return number_or_empty(r.machine_temp_C); }},
    };
    const std::vector<std::string> required = {"X_mm",        "Y_mm",        "Z_mm",        all[7].name,
                                               all[8].name,   "socket_x_mm", "socket_y_mm", "socket_z_mm",
                                               "measured_mm", "nominal_mm"};
    std::vector<Column> cols;
    for (auto& c : all) {
        bool keep = std::find(required.begin(), required.end(), c.name) != required.end();
        for (std::size_t i = 0; !keep && i < set.readings.size(); ++i) keep = !c.value(set.readings[i]).empty();
        if (keep) cols.push_back(std::move(c));
    }
    for (std::size_t i = 0; i < cols.size(); ++i) out += (i ? "," : "") + cols[i].name;
    out += '\n';
    for (const auto& r : set.readings) {
        for (std::size_t i = 0; i < cols.size(); ++i) {
            if (i) out += ',';
            out += cols[i].value(r);
        }
        out += '\n';
    }
    return out;
}

void write_readings_file(const std::filesystem::path& path, const analysis::ReadingSet& set,
                         const ReadingsMetadata& metadata) {
    const std::string text = format_readings(set, metadata);
    try {  // an exclusive temporary file renamed over `path`; never through a symlink
        fileio::write_file(path.string(), "output", text);
    } catch (const fileio::FileError& e) {
        throw std::runtime_error(e.what());
    }
}

}  // namespace ballbar::storage
