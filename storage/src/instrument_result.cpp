// SPDX-License-Identifier: MIT
#include "ballbar/storage/instrument_result.hpp"

#include <nlohmann/json.hpp>

#include "ballbar/fileio/json_fields.hpp"
#include "ballbar/storage/machine_json.hpp"

namespace ballbar::storage {
namespace {

using json = nlohmann::json;

[[noreturn]] void bad_instrument(const std::string& key, const std::string& problem) {
    throw FormatError("result \"instrument\"" + (key.empty() ? "" : ": \"" + key + "\"") + " " + problem);
}
using InstrumentFields = fileio::JsonFields<json, decltype(&bad_instrument)>;

std::optional<std::string> optional_text(const InstrumentFields& f, const char* key) {
    const json* v = f.optional(key);
    if (!v) return std::nullopt;
    if (!v->is_string()) f.refuse(key, "must be a string or null");
    return v->get<std::string>();
}

}  // namespace

std::string gauge_instrument_to_json(const GaugeInstrumentRecord& r) {
    json j;
    if (!r.kind.empty()) {
        j["kind"] = r.kind;
        j["maker"] = r.maker;
        j["model"] = r.model;
        // Missing is null, not "" (docs/cli.md's vocabulary).
        j["serial"] = r.serial ? json(*r.serial) : json(nullptr);
        j["firmware"] = r.firmware ? json(*r.firmware) : json(nullptr);
        j["inch"] = r.inch;
        j["low_battery"] = r.low_battery;
    }
    j["uri"] = r.uri;
    j["resolution_mm"] = r.resolution_mm;
    j["reading_rate_hz"] = r.reading_rate_hz;
    j["target_rate_hz"] = r.target_rate_hz;
    j["calibrated_length_mm"] = r.calibrated_length_mm;
    j["sign"] = r.sign;
    j["readings"] = r.readings;
    j["not_ready"] = r.not_ready;
    j["out_of_range"] = r.out_of_range;
    j["timeouts"] = r.timeouts;
    j["invalid"] = r.invalid;
    j["errors"] = r.errors;
    return j.dump();
}

GaugeInstrumentRecord gauge_instrument_from_json(std::string_view text) {
    json j;
    try {
        j = json::parse(text);
    } catch (const json::exception& e) {
        throw FormatError(std::string("result \"instrument\" is not valid JSON: ") + e.what());
    }
    const InstrumentFields f(j, "", &bad_instrument);
    f.only({"kind", "maker", "model", "serial", "firmware", "inch", "low_battery", "uri", "resolution_mm",
            "reading_rate_hz", "target_rate_hz", "calibrated_length_mm", "sign", "readings", "not_ready",
            "out_of_range", "timeouts", "invalid", "errors"});
    GaugeInstrumentRecord r;
    if (f.has("kind")) {  // identified
        r.kind = f.text("kind");
        r.maker = f.text("maker");
        r.model = f.text("model");
        r.serial = optional_text(f, "serial");
        r.firmware = optional_text(f, "firmware");
        r.inch = f.boolean("inch");
        r.low_battery = f.boolean("low_battery");
    }
    r.uri = f.text("uri");
    r.resolution_mm = f.number("resolution_mm");
    r.reading_rate_hz = f.number("reading_rate_hz");
    r.target_rate_hz = f.number("target_rate_hz");
    r.calibrated_length_mm = f.number("calibrated_length_mm");
    r.sign = f.number("sign") < 0 ? -1 : 1;
    r.readings = static_cast<std::uint64_t>(f.count("readings", std::numeric_limits<std::int64_t>::max()));
    r.not_ready = static_cast<std::uint64_t>(f.count("not_ready", std::numeric_limits<std::int64_t>::max()));
    r.out_of_range = static_cast<std::uint64_t>(f.count("out_of_range", std::numeric_limits<std::int64_t>::max()));
    r.timeouts = static_cast<std::uint64_t>(f.count("timeouts", std::numeric_limits<std::int64_t>::max()));
    r.invalid = static_cast<std::uint64_t>(f.count("invalid", std::numeric_limits<std::int64_t>::max()));
    r.errors = static_cast<std::uint64_t>(f.count("errors", std::numeric_limits<std::int64_t>::max()));
    return r;
}

}  // namespace ballbar::storage
