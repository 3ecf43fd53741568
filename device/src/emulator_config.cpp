// SPDX-License-Identifier: MIT
// The emulator's JSON configuration (docs/emulator.md).
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "ballbar/analysis/limits.hpp"
#include "ballbar/device/emulator.hpp"
#include "ballbar/fileio/input.hpp"
#include "ballbar/fileio/json_fields.hpp"

namespace ballbar::device {

using nlohmann::json;

namespace {

[[noreturn]] void fail(const std::string& key, const std::string& what) {
    throw std::invalid_argument("emulator config: " + key + ": " + what);
}

/// Refuses a key not in `allowed` (fileio/json_fields.hpp): `emulator config: machine: unknown key "x"
/// (known: …)`.
void only_keys(const json& obj, const std::string& where, std::initializer_list<std::string_view> allowed) {
    if (!obj.is_object()) fail(where, "must be an object");
    const auto refuse = [](const std::string& path, const std::string& problem) {
        throw std::invalid_argument("emulator config: " + (path.empty() ? problem : path + ": " + problem));
    };
    fileio::JsonFields<json, decltype(refuse)>(obj, where, refuse).only_known(allowed);
}

double num(const json& obj, const std::string& where, const char* key, double fallback) {
    if (!obj.contains(key)) return fallback;
    const auto& v = obj.at(key);
    if (!v.is_number()) fail(where + "." + key, "must be a number");
    return v.get<double>();
}

/// A number within its documented range (docs/emulator.md, "Ranges"), or the default when absent.
double num_in(const json& obj, const std::string& where, const char* key, double fallback, double lo, double hi,
              std::string_view unit) {
    const double v = num(obj, where, key, fallback);
    if (const std::string why = analysis::limits::check_in(v, lo, hi, unit); !why.empty())
        throw std::invalid_argument("emulator config: " + where + "." + key + " " + why);
    return v;
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
    const analysis::Vec3 out(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
    for (int i = 0; i < 3; ++i) {
        if (const std::string why = analysis::limits::check_in(out[i], -analysis::limits::kPosition_mm,
                                                               analysis::limits::kPosition_mm, "mm");
            !why.empty())
            throw std::invalid_argument("emulator config: " + where + "." + key + "[" + std::to_string(i) + "] " + why);
    }
    return out;
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
    m.noise_um = num_in(j, w, "noise_um", m.noise_um, 0, 1000, "um");
    m.zero_offset_um = num_in(j, w, "zero_offset_um", m.zero_offset_um, -1000, 1000, "um");
    const double rate = num(j, w, "sample_rate_hz", m.sample_rate_hz);
    if (!(rate >= 1 && rate <= 5000) || rate != std::floor(rate))
        fail(w + ".sample_rate_hz", "must be an integer 1..5000");
    m.sample_rate_hz = static_cast<std::uint16_t>(rate);
    const double avg = num(j, w, "averaging", m.averaging);
    if (!(avg >= 1 && avg <= 64) || avg != std::floor(avg)) fail(w + ".averaging", "must be an integer 1..64");
    m.averaging = static_cast<std::uint8_t>(avg);
    namespace lim = analysis::limits;
    m.temp_start_C = num_in(j, w, "temp_start_C", m.temp_start_C, lim::kTempMin_C, lim::kTempMax_C, "C");
    m.temp_drift_C_per_h = num_in(j, w, "temp_drift_C_per_h", m.temp_drift_C_per_h, -100, 100, "C/h");
    m.temp_ripple_C = num_in(j, w, "temp_ripple_C", m.temp_ripple_C, 0, 100, "C");
    m.temp_ripple_period_s = num_in(j, w, "temp_ripple_period_s", m.temp_ripple_period_s, 0.001, 1e6, "s");
    m.battery_start_pct = num_in(j, w, "battery_start_pct", m.battery_start_pct, 0, 100, "%");
    m.battery_drain_pct_per_h = num_in(j, w, "battery_drain_pct_per_h", m.battery_drain_pct_per_h, 0, 1000, "%/h");
    m.watchdog_s = num_in(j, w, "watchdog_s", m.watchdog_s, 0, 3600, "s");
}

analysis::Pose parse_pose(const json& j, const std::string& w, const analysis::Pose& fallback) {
    only_keys(j, w, {"X_mm", "Y_mm", "Z_mm", "A_deg", "B_deg", "C_deg"});
    analysis::Pose p;
    namespace lim = analysis::limits;
    auto mm = [&](const char* key, double fb) {
        return num_in(j, w, key, fb, -lim::kPosition_mm, lim::kPosition_mm, "mm");
    };
    auto deg = [&](const char* key, double fb_rad) {
        return analysis::deg_to_rad(
            num_in(j, w, key, analysis::rad_to_deg(fb_rad), -lim::kRotary_deg, lim::kRotary_deg, "deg"));
    };
    p.X_mm = mm("X_mm", fallback.X_mm);
    p.Y_mm = mm("Y_mm", fallback.Y_mm);
    p.Z_mm = mm("Z_mm", fallback.Z_mm);
    p.A_rad = deg("A_deg", fallback.A_rad);
    p.B_rad = deg("B_deg", fallback.B_rad);
    p.C_rad = deg("C_deg", fallback.C_rad);
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
        if (const std::string why = analysis::limits::check_param(*param, e[*param]); !why.empty())
            fail(w, name + " " + why);
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
    m.rapid_mm_min = num_in(j, w, "rapid_mm_min", m.rapid_mm_min, 1, 1e6, "mm/min");
    m.rapid_deg_min = num_in(j, w, "rapid_deg_min", m.rapid_deg_min, 1, 1e6, "deg/min");
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
    f.start_delay_s = num_in(j, w, "start_delay_s", f.start_delay_s, 0, 3600, "s");
    f.feed_override = num(j, w, "feed_override", f.feed_override);
    f.answer_delay_s = num(j, w, "answer_delay_s", f.answer_delay_s);
    if (!(f.answer_delay_s >= 0 && f.answer_delay_s <= 3600)) fail(w + ".answer_delay_s", "must be in [0, 3600]");
    if (!(f.feed_override >= 0.1 && f.feed_override <= 2.0)) fail(w + ".feed_override", "must be in [0.1, 2]");
    for (const auto& [key, pr] : {std::pair{"drop_frame_probability", f.drop_frame_probability},
                                  std::pair{"corrupt_byte_probability", f.corrupt_byte_probability},
                                  std::pair{"replay_frame_probability", f.replay_frame_probability}}) {
        if (!(pr >= 0 && pr <= 1)) fail(w + "." + key, "probabilities must be in [0, 1]");
    }
    // Times of the session's clock; -1 (or any negative time) means never.
    f.stall_at_s = num_in(j, w, "stall_at_s", f.stall_at_s, -1e9, 1e9, "s");
    f.stall_s = num_in(j, w, "stall_s", f.stall_s, 0, 1e6, "s");
    f.disconnect_at_s = num_in(j, w, "disconnect_at_s", f.disconnect_at_s, -1e9, 1e9, "s");
    f.disconnect_s = num_in(j, w, "disconnect_s", f.disconnect_s, 0, 1e6, "s");
    f.reply_delay_ms = num_in(j, w, "reply_delay_ms", f.reply_delay_ms, 0, 60'000, "ms");
}

// "continuous": the continuous machine's errors, per axis {"X", "Y", "Z"}, per plane {"XY", "YZ", "ZX"}.
void parse_continuous(const json& j, ContinuousErrors& e) {
    const std::string w = "continuous";
    static constexpr const char* per_axis[] = {"servo_lag_ms", "backlash_um",     "reversal_spike_um", "scale_ppm",
                                               "cyclic_um",    "cyclic_pitch_mm", "cyclic_phase_deg"};
    only_keys(j, w,
              {"servo_lag_ms", "backlash_um", "reversal_spike_um", "scale_ppm", "cyclic_um", "cyclic_pitch_mm",
               "cyclic_phase_deg", "squareness_um_per_m", "straightness_um_per_m2", "vibration_um", "vibration_hz",
               "vibration_phase_deg"});
    for (const std::string key : per_axis) {
        if (!j.contains(key)) continue;
        const std::string wk = w + "." + key;
        only_keys(j.at(key), wk, {"X", "Y", "Z"});
        for (std::size_t a = 0; a < 3; ++a) {
            const char name[2] = {"XYZ"[a], 0};
            AxisErrors& ax = e.axis[a];
            double* field = key == "servo_lag_ms"        ? &ax.servo_lag_ms
                            : key == "backlash_um"       ? &ax.backlash_um
                            : key == "reversal_spike_um" ? &ax.reversal_spike_um
                            : key == "scale_ppm"         ? &ax.scale_ppm
                            : key == "cyclic_um"         ? &ax.cyclic_um
                            : key == "cyclic_pitch_mm"   ? &ax.cyclic_pitch_mm
                                                         : &ax.cyclic_phase_deg;
            *field = num(j.at(key), wk, name, *field);
            if (!std::isfinite(*field)) fail(wk + "." + name, "must be a finite number");
        }
    }
    for (std::size_t a = 0; a < 3; ++a) {
        const std::string axis(1, "XYZ"[a]);
        if (!(e.axis[a].servo_lag_ms >= 0 && e.axis[a].servo_lag_ms <= 1000))
            fail(w + ".servo_lag_ms." + axis, "must be in [0, 1000] ms");
        if (!(e.axis[a].cyclic_pitch_mm >= 0)) fail(w + ".cyclic_pitch_mm." + axis, "must not be negative");
        if (e.axis[a].cyclic_um != 0 && !(e.axis[a].cyclic_pitch_mm > 0))
            fail(w + ".cyclic_pitch_mm." + axis, "a cyclic error needs its pitch (> 0 mm)");
    }
    if (j.contains("squareness_um_per_m")) {
        const std::string wk = w + ".squareness_um_per_m";
        only_keys(j.at("squareness_um_per_m"), wk, {"XY", "YZ", "ZX"});
        const char* planes[3] = {"XY", "YZ", "ZX"};
        for (std::size_t i = 0; i < 3; ++i)
            e.squareness_um_per_m[i] = num(j.at("squareness_um_per_m"), wk, planes[i], e.squareness_um_per_m[i]);
    }
    if (j.contains("straightness_um_per_m2")) {
        const std::string wk = w + ".straightness_um_per_m2";
        only_keys(j.at("straightness_um_per_m2"), wk, {"x_in_y", "x_in_z", "y_in_x", "y_in_z", "z_in_x", "z_in_y"});
        for (std::size_t a = 0; a < 3; ++a)
            for (std::size_t b = 0; b < 3; ++b) {
                if (a == b) continue;
                const std::string key = std::string(1, "xyz"[a]) + "_in_" + "xyz"[b];
                e.straightness_um_per_m2[a][b] =
                    num(j.at("straightness_um_per_m2"), wk, key.c_str(), e.straightness_um_per_m2[a][b]);
            }
    }
    e.vibration_um = num(j, w, "vibration_um", e.vibration_um);
    e.vibration_hz = num(j, w, "vibration_hz", e.vibration_hz);
    e.vibration_phase_deg = num(j, w, "vibration_phase_deg", e.vibration_phase_deg);
    if (!(e.vibration_hz >= 0 && e.vibration_hz <= 2500)) fail(w + ".vibration_hz", "must be in [0, 2500] Hz");
}

/// A configuration (at most fileio::kMaxJsonBytes) or an NC program (fileio::kMaxTextBytes).
std::string read_file(const std::string& path, const char* what, bool program = false) {
    try {
        return program ? fileio::read_text(path, what) : fileio::read_json(path, what);
    } catch (const fileio::FileError& e) {
        throw std::invalid_argument(e.what());
    }
}

}  // namespace

EmulatorConfig parse_emulator_config(std::string_view json_text, const std::string& base_dir) {
    json j;
    try {
        fileio::check_json_nesting(json_text, "emulator config");  // also the inline --faults
        j = json::parse(json_text);
    } catch (const json::exception& e) {  // parse_error, and out_of_range for a number past double
        throw std::invalid_argument(std::string("emulator config: not valid JSON: ") + e.what());
    } catch (const fileio::FileError& e) {
        throw std::invalid_argument(e.what());
    }
    EmulatorConfig c;
    only_keys(j, "", {"seed", "time", "instrument", "machine", "program", "faults", "continuous"});
    if (j.contains("time")) {
        const json& t = j.at("time");
        if (!t.is_string() || (t != "real" && t != "simulated")) fail("time", "must be \"real\" or \"simulated\"");
        c.simulated_time = t == "simulated";
    }
    if (j.contains("seed")) {
        if (!j.at("seed").is_number_unsigned()) fail("seed", "must be a non-negative integer");
        c.seed = j.at("seed").get<std::uint64_t>();
    }
    if (j.contains("instrument")) parse_instrument(j.at("instrument"), c.instrument);
    if (j.contains("machine")) parse_machine(j.at("machine"), c.machine);
    if (j.contains("faults")) parse_faults(j.at("faults"), c.faults);
    if (j.contains("continuous")) {
        c.continuous.emplace();
        parse_continuous(j.at("continuous"), *c.continuous);
    }
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
            if (c.continuous)  // arcs: the continuous machine's own reader
                parse_motion_program(src.text, src.dialect, {0, 0, 0}, 1.0);
            else
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
