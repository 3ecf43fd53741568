// SPDX-License-Identifier: MIT
#include "ballbar/storage/identification_codec.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "ballbar/storage/machine_json.hpp"

namespace ballbar::storage {
namespace {

namespace ba = ballbar::analysis;
using json = nlohmann::ordered_json;

constexpr std::string_view kKeys[] = {"converged",
                                      "iterations",
                                      "message",
                                      "readings",
                                      "degrees_of_freedom",
                                      "residual_rms_um",
                                      "residual_sigma_um",
                                      "noise_floor_um",
                                      "uncertainty_from_noise_floor",
                                      "initial_rms_um",
                                      "estimates",
                                      "correlation",
                                      "correlation_names",
                                      "model"};
constexpr std::string_view kEstimateKeys[] = {"name",         "estimate",   "std", "sensitivity",
                                              "independence", "observable", "unit"};

[[noreturn]] void bad(const std::string& key, const std::string& what) {
    throw FormatError("result \"identification\": \"" + key + "\" " + what);
}

/// A number; null (what nlohmann writes for NaN and ±∞) reads as NaN where `nan_ok`.
double number(const json& v, const std::string& key, bool nan_ok = false) {
    if (nan_ok && v.is_null()) return std::numeric_limits<double>::quiet_NaN();
    if (!v.is_number() || !std::isfinite(v.get<double>())) bad(key, "must be a finite number");
    return v.get<double>();
}
int count(const json& v, const std::string& key) {
    if (!v.is_number_integer() || v.get<std::int64_t>() < 0 || v.get<std::int64_t>() > 2'000'000'000)
        bad(key, "must be a non-negative integer");
    return v.get<int>();
}
bool boolean(const json& v, const std::string& key) {
    if (!v.is_boolean()) bad(key, "must be true or false");
    return v.get<bool>();
}
std::string text(const json& v, const std::string& key) {
    if (!v.is_string()) bad(key, "must be a string");
    return v.get<std::string>();
}
template <std::size_t N>
void only(const json& j, const std::string_view (&keys)[N], const std::string& where) {
    for (const auto& item : j.items())
        if (std::find(std::begin(keys), std::end(keys), item.key()) == std::end(keys))
            bad(where + item.key(), "is not a key it has");
}

}  // namespace

std::string identification_to_json(const ba::FitSummary& fit, const ErrorModel& model) {
    json j;
    j["converged"] = fit.converged;
    j["iterations"] = fit.iterations;
    j["message"] = fit.message;
    j["readings"] = fit.readings;
    j["degrees_of_freedom"] = fit.degrees_of_freedom;
    j["residual_rms_um"] = fit.residual_rms_mm * 1e3;
    j["residual_sigma_um"] = fit.residual_sigma_mm * 1e3;
    j["noise_floor_um"] = fit.noise_floor_mm * 1e3;
    j["uncertainty_from_noise_floor"] = fit.uncertainty_from_floor;
    j["initial_rms_um"] = fit.initial_rms_mm * 1e3;
    j["estimates"] = json::array();
    for (const auto& e : fit.estimates)
        j["estimates"].push_back(
            {{"name", e.name},
             {"estimate", e.estimate},
             {"std", e.std},
             {"sensitivity", e.sensitivity},
             {"independence", e.independence},
             {"observable", e.observable},
             {"unit", e.param ? std::string(ba::to_string(ba::param_info(*e.param).unit)) : std::string("mm")}});
    j["correlation"] = json::array();
    for (Eigen::Index r = 0; r < fit.correlation.rows(); ++r) {
        json row = json::array();
        for (Eigen::Index c = 0; c < fit.correlation.cols(); ++c) row.push_back(fit.correlation(r, c));
        j["correlation"].push_back(row);
    }
    j["correlation_names"] = json::array();
    for (std::size_t i : fit.fitted) j["correlation_names"].push_back(fit.estimates[i].name);
    j["model"] = json::parse(model_to_json(model));
    return j.dump();
}

IdentificationRecord identification_from_json(std::string_view text_in) {
    json j;
    try {
        j = json::parse(text_in);
    } catch (const json::exception& e) {
        throw FormatError(std::string("result \"identification\" is not valid JSON: ") + e.what());
    }
    if (!j.is_object()) throw FormatError("result \"identification\" is not a JSON object");
    only(j, kKeys, "");
    for (const char* key : {"converged", "residual_rms_um", "estimates"})
        if (!j.contains(key)) bad(key, "is missing");
    IdentificationRecord r;
    r.converged = boolean(j["converged"], "converged");
    r.residual_rms_um = number(j["residual_rms_um"], "residual_rms_um");
    if (j.contains("iterations")) r.iterations = count(j["iterations"], "iterations");
    if (j.contains("message")) r.message = text(j["message"], "message");
    if (j.contains("readings")) r.readings = count(j["readings"], "readings");
    if (j.contains("degrees_of_freedom")) r.degrees_of_freedom = count(j["degrees_of_freedom"], "degrees_of_freedom");
    if (j.contains("residual_sigma_um")) r.residual_sigma_um = number(j["residual_sigma_um"], "residual_sigma_um");
    if (j.contains("initial_rms_um")) r.initial_rms_um = number(j["initial_rms_um"], "initial_rms_um");
    if (j.contains("noise_floor_um")) r.noise_floor_um = number(j["noise_floor_um"], "noise_floor_um");
    if (j.contains("uncertainty_from_noise_floor"))
        r.uncertainty_from_noise_floor = boolean(j["uncertainty_from_noise_floor"], "uncertainty_from_noise_floor");
    if (!j["estimates"].is_array()) bad("estimates", "must be an array");
    for (std::size_t i = 0; i < j["estimates"].size(); ++i) {
        const json& e = j["estimates"][i];
        const std::string at = "estimates[" + std::to_string(i) + "].";
        if (!e.is_object()) bad(at.substr(0, at.size() - 1), "must be an object");
        only(e, kEstimateKeys, at);
        for (const char* key : {"name", "estimate", "std", "observable", "unit"})
            if (!e.contains(key)) bad(at + key, "is missing");
        IdentifiedEstimate x;
        x.name = text(e["name"], at + "name");
        x.estimate = number(e["estimate"], at + "estimate");
        x.std = number(e["std"], at + "std", /*nan_ok=*/true);
        if (e.contains("sensitivity")) x.sensitivity = number(e["sensitivity"], at + "sensitivity", true);
        if (e.contains("independence")) x.independence = number(e["independence"], at + "independence", true);
        x.observable = boolean(e["observable"], at + "observable");
        x.unit = text(e["unit"], at + "unit");
        r.estimates.push_back(std::move(x));
    }
    if (j.contains("correlation_names")) {
        if (!j["correlation_names"].is_array()) bad("correlation_names", "must be an array of names");
        for (const auto& n : j["correlation_names"]) r.correlation_names.push_back(text(n, "correlation_names"));
    }
    if (j.contains("correlation")) {
        const json& c = j["correlation"];
        if (!c.is_array() || c.size() != r.correlation_names.size())
            bad("correlation", "must be a square matrix over correlation_names");
        for (const auto& row : c) {
            if (!row.is_array() || row.size() != r.correlation_names.size())
                bad("correlation", "must be a square matrix over correlation_names");
            auto& out = r.correlation.emplace_back();
            for (const auto& v : row) out.push_back(number(v, "correlation", /*nan_ok=*/true));
        }
    }
    if (j.contains("model")) {
        try {
            r.model = model_from_json(j["model"].dump());
        } catch (const FormatError& e) {
            bad("model", std::string("is not a model: ") + e.what());
        }
    }
    return r;
}

}  // namespace ballbar::storage
