// SPDX-License-Identifier: MIT
// The emulator's JSON configuration (docs/emulator.md).
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <stdexcept>

#include "ballbar/device/emulator.hpp"
#include "ballbar/fileio/input.hpp"

namespace ballbar::device {

using nlohmann::json;

namespace {

[[noreturn]] void fail(const std::string& key, const std::string& what) {
    throw std::invalid_argument("emulator config: " + key + ": " + what);
}

void only_keys(const json& obj, const std::string& where, const std::set<std::string>& allowed) {
    if (!obj.is_object()) fail(where, "must be an object");
    for (const auto& [k, v] : obj.items()) {
        if (!allowed.count(k)) fail(where.empty() ? k : where + "." + k, "unknown key");
    }
}

double num(const json& obj, const std::string& where, const char* key, double fallback) {
    if (!obj.contains(key)) return fallback;
    const auto& v = obj.at(key);
    if (!v.is_number()) fail(where + "." + key, "must be a number");
    return v.get<double>();
}

std::string str(const json& obj, const std::string& where, const char* key, const std::string& fallback) {
    if (!obj.contains(key)) return fallback;
    const auto& v = obj.at(key);
    if (!v.is_string()) fail(where + "." + key, "must be a string");
    return v.get<std::string>();
}

analysis::Vec3 vec3(const json& obj, const std::string& where, const char* key, const analysis::Vec3& fallback) {
    if (!obj.contains(key)) return fallback;
    const auto& v = obj.at(key);
    if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number()) {
        fail(where + "." + key, "must be an array of three numbers [x, y, z] in mm");
    }
    return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
}

void parse_instrument(const json& j, InstrumentModel& m) {
    const std::string w = "instrument";
    only_keys(j, w,
              {"model", "serial", "firmware", "calibrated_length_mm", "calibration_date", "noise_um", "zero_offset_um",
               "sample_rate_hz", "averaging", "temp_start_C", "temp_drift_C_per_h", "temp_ripple_C",
               "temp_ripple_period_s", "battery_start_pct", "battery_drain_pct_per_h", "watchdog_s"});
    m.model = str(j, w, "model", m.model);
    m.serial = str(j, w, "serial", m.serial);
    m.firmware = str(j, w, "firmware", m.firmware);
    if (m.model.size() > 12 || m.serial.size() > 12 || m.firmware.size() > 8) {
        fail(w, "model and serial take at most 12 characters, firmware 8");
    }
    m.calibrated_length_mm = num(j, w, "calibrated_length_mm", m.calibrated_length_mm);
    m.calibration_date = str(j, w, "calibration_date", m.calibration_date);
    if (!protocol::parse_calibration_date(m.calibration_date))
        fail(w + ".calibration_date", "must be a date YYYY-MM-DD (or \"\")");
    if (!(m.calibrated_length_mm > 0 && m.calibrated_length_mm < 4000))
        fail(w + ".calibrated_length_mm", "must be in (0, 4000)");
    m.noise_um = num(j, w, "noise_um", m.noise_um);
    if (!(m.noise_um >= 0)) fail(w + ".noise_um", "must not be negative");
    m.zero_offset_um = num(j, w, "zero_offset_um", m.zero_offset_um);
    const double rate = num(j, w, "sample_rate_hz", m.sample_rate_hz);
    if (!(rate >= 1 && rate <= 5000) || rate != std::floor(rate))
        fail(w + ".sample_rate_hz", "must be an integer 1..5000");
    m.sample_rate_hz = static_cast<std::uint16_t>(rate);
    const double avg = num(j, w, "averaging", m.averaging);
    if (!(avg >= 1 && avg <= 64) || avg != std::floor(avg)) fail(w + ".averaging", "must be an integer 1..64");
    m.averaging = static_cast<std::uint8_t>(avg);
    m.temp_start_C = num(j, w, "temp_start_C", m.temp_start_C);
    m.temp_drift_C_per_h = num(j, w, "temp_drift_C_per_h", m.temp_drift_C_per_h);
    m.temp_ripple_C = num(j, w, "temp_ripple_C", m.temp_ripple_C);
    m.temp_ripple_period_s = num(j, w, "temp_ripple_period_s", m.temp_ripple_period_s);
    m.battery_start_pct = num(j, w, "battery_start_pct", m.battery_start_pct);
    m.battery_drain_pct_per_h = num(j, w, "battery_drain_pct_per_h", m.battery_drain_pct_per_h);
    m.watchdog_s = num(j, w, "watchdog_s", m.watchdog_s);
}

analysis::Pose parse_pose(const json& j, const std::string& w, const analysis::Pose& fallback) {
    only_keys(j, w, {"X_mm", "Y_mm", "Z_mm", "A_deg", "B_deg", "C_deg"});
    analysis::Pose p;
    p.X_mm = num(j, w, "X_mm", fallback.X_mm);
    p.Y_mm = num(j, w, "Y_mm", fallback.Y_mm);
    p.Z_mm = num(j, w, "Z_mm", fallback.Z_mm);
    p.A_rad = analysis::deg_to_rad(num(j, w, "A_deg", analysis::rad_to_deg(fallback.A_rad)));
    p.B_rad = analysis::deg_to_rad(num(j, w, "B_deg", analysis::rad_to_deg(fallback.B_rad)));
    p.C_rad = analysis::deg_to_rad(num(j, w, "C_deg", analysis::rad_to_deg(fallback.C_rad)));
    return p;
}

// Error parameters by name in their own unit ("X0C": mm, "B0A": rad), or with a suffix: "_um" for
// mm parameters, "_deg"/"_urad"/"_arcsec" for angles.
void parse_errors(const json& j, analysis::ErrorParams& e) {
    if (!j.is_object()) fail("machine.errors", "must be an object");
    for (const auto& [key, value] : j.items()) {
        const std::string w = "machine.errors." + key;
        if (!value.is_number()) fail(w, "must be a number");
        std::string name = key;
        double scale = 1;
        auto strip = [&](std::string_view suffix, double s) {
            if (name.size() > suffix.size() && name.ends_with(suffix)) {
                name.resize(name.size() - suffix.size());
                scale = s;
                return true;
            }
            return false;
        };
        const bool suffixed = strip("_um", 1e-3) || strip("_deg", analysis::kPi / 180.0) || strip("_urad", 1e-6) ||
                              strip("_arcsec", analysis::kPi / 180.0 / 3600.0);
        const auto param = analysis::parse_param(name);
        if (!param) fail(w, "unknown error parameter (see docs/emulator.md for the names)");
        const auto unit = analysis::param_info(*param).unit;
        if (suffixed) {
            const bool length_suffix = key.ends_with("_um");
            if (length_suffix != (unit == analysis::ParamUnit::mm) ||
                (!length_suffix && unit != analysis::ParamUnit::rad)) {
                fail(w,
                     "this suffix does not fit the parameter's unit (" + std::string(analysis::to_string(unit)) + ")");
            }
        }
        e[*param] = value.get<double>() * scale;
    }
}

void parse_machine(const json& j, MachineSetup& m) {
    const std::string w = "machine";
    only_keys(j, w,
              {"type", "name", "tool_ball_mm", "a_pivot_mm", "c_offset_mm", "socket_mm", "socket_offset_mm", "start",
               "rapid_mm_min", "rapid_deg_min", "errors"});
    if (j.contains("type")) {
        const auto t = analysis::parse_machine_type(str(j, w, "type", ""));
        if (!t) fail(w + ".type", "must be RRTTT, TTTRR or RTTTR");
        m.geometry.type = *t;
    }
    m.geometry.name = str(j, w, "name", m.geometry.name);
    m.geometry.tool_ball_mm = vec3(j, w, "tool_ball_mm", m.geometry.tool_ball_mm);
    m.geometry.a_pivot_mm = vec3(j, w, "a_pivot_mm", m.geometry.a_pivot_mm);
    m.geometry.c_offset_mm = vec3(j, w, "c_offset_mm", m.geometry.c_offset_mm);
    m.socket_mm = vec3(j, w, "socket_mm", m.socket_mm);
    m.socket_offset_mm = vec3(j, w, "socket_offset_mm", m.socket_offset_mm);
    if (j.contains("start")) m.start = parse_pose(j.at("start"), w + ".start", m.start);
    m.rapid_mm_min = num(j, w, "rapid_mm_min", m.rapid_mm_min);
    m.rapid_deg_min = num(j, w, "rapid_deg_min", m.rapid_deg_min);
    if (!(m.rapid_mm_min > 0 && m.rapid_deg_min > 0)) fail(w, "rapid speeds must be positive");
    if (j.contains("errors")) parse_errors(j.at("errors"), m.errors);
}

void parse_faults(const json& j, FaultConfig& f) {
    const std::string w = "faults";
    only_keys(j, w,
              {"drop_frame_probability", "corrupt_byte_probability", "stall_at_s", "stall_s", "disconnect_at_s",
               "disconnect_s", "reply_delay_ms", "replay_frame_probability", "start_delay_s", "feed_override",
               "answer_delay_s"});
    f.drop_frame_probability = num(j, w, "drop_frame_probability", f.drop_frame_probability);
    f.corrupt_byte_probability = num(j, w, "corrupt_byte_probability", f.corrupt_byte_probability);
    f.replay_frame_probability = num(j, w, "replay_frame_probability", f.replay_frame_probability);
    f.start_delay_s = num(j, w, "start_delay_s", f.start_delay_s);
    f.feed_override = num(j, w, "feed_override", f.feed_override);
    f.answer_delay_s = num(j, w, "answer_delay_s", f.answer_delay_s);
    if (!(f.start_delay_s >= 0)) fail(w + ".start_delay_s", "must not be negative");
    if (!(f.answer_delay_s >= 0 && f.answer_delay_s <= 3600)) fail(w + ".answer_delay_s", "must be in [0, 3600]");
    if (!(f.feed_override >= 0.1 && f.feed_override <= 2.0)) fail(w + ".feed_override", "must be in [0.1, 2]");
    for (double pr : {f.drop_frame_probability, f.corrupt_byte_probability, f.replay_frame_probability}) {
        if (!(pr >= 0 && pr <= 1)) fail(w, "probabilities must be in [0, 1]");
    }
    f.stall_at_s = num(j, w, "stall_at_s", f.stall_at_s);
    f.stall_s = num(j, w, "stall_s", f.stall_s);
    f.disconnect_at_s = num(j, w, "disconnect_at_s", f.disconnect_at_s);
    f.disconnect_s = num(j, w, "disconnect_s", f.disconnect_s);
    f.reply_delay_ms = num(j, w, "reply_delay_ms", f.reply_delay_ms);
    if (f.stall_s < 0 || f.disconnect_s < 0 || f.reply_delay_ms < 0) fail(w, "durations must not be negative");
}

/// A configuration (at most fileio::kMaxJsonBytes) or an NC program (fileio::kMaxTextBytes).
std::string read_file(const std::string& path, const char* what, bool program = false) {
    try {
        return program ? fileio::read_text(path, what) : fileio::read_whole(path, what, fileio::kMaxJsonBytes);
    } catch (const fileio::FileError& e) {
        throw std::invalid_argument(e.what());
    }
}

}  // namespace

EmulatorConfig parse_emulator_config(std::string_view json_text, const std::string& base_dir) {
    json j;
    try {
        j = json::parse(json_text);
    } catch (const json::parse_error& e) {
        throw std::invalid_argument(std::string("emulator config: not valid JSON: ") + e.what());
    }
    EmulatorConfig c;
    only_keys(j, "", {"seed", "instrument", "machine", "program", "faults"});
    if (j.contains("seed")) {
        if (!j.at("seed").is_number_unsigned()) fail("seed", "must be a non-negative integer");
        c.seed = j.at("seed").get<std::uint64_t>();
    }
    if (j.contains("instrument")) parse_instrument(j.at("instrument"), c.instrument);
    if (j.contains("machine")) parse_machine(j.at("machine"), c.machine);
    if (j.contains("faults")) parse_faults(j.at("faults"), c.faults);
    if (j.contains("program")) {
        const auto& pj = j.at("program");
        only_keys(pj, "program", {"file", "text", "dialect", "start"});

        NcSource src;
        if (pj.contains("start")) {
            const std::string st = str(pj, "program", "start", "");
            if (st != "cycle_start" && st != "power_on") fail("program.start", "must be cycle_start or power_on");
            src.power_on = st == "power_on";
        }
        if (pj.contains("dialect")) {
            const auto d = analysis::parse_nc_dialect(str(pj, "program", "dialect", ""));
            if (!d) fail("program.dialect", "must be fanuc or linuxcnc");
            src.dialect = *d;
        }
        if (pj.contains("file") == pj.contains("text")) fail("program", "give exactly one of \"file\" and \"text\"");
        if (pj.contains("text")) {
            src.text = str(pj, "program", "text", "");
        } else {
            std::filesystem::path f = str(pj, "program", "file", "");
            if (f.is_relative()) f = std::filesystem::path(base_dir) / f;
            src.file = f.string();
            // Waiting for cycle start, the file may not exist yet: the host writes it before the start.
            if (src.power_on || std::filesystem::exists(f)) src.text = read_file(f.string(), "NC program", true);
        }
        try {
            analysis::parse_nc_program(src.text, src.dialect);  // fail now, with the line number
        } catch (const analysis::NcError& e) {
            fail("program", e.what());
        }
        c.program = std::move(src);
    }
    return c;
}

EmulatorConfig load_emulator_config(const std::string& path) {
    const auto dir = std::filesystem::path(path).parent_path();
    return parse_emulator_config(read_file(path, "emulator configuration"), dir.empty() ? "." : dir.string());
}

}  // namespace ballbar::device
