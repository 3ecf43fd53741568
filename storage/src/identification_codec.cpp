// SPDX-License-Identifier: MIT
#include "ballbar/storage/identification_codec.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "ballbar/fileio/json_fields.hpp"
#include "ballbar/storage/machine_json.hpp"

namespace ballbar::storage {
namespace {

namespace ba = ballbar::analysis;
using ojson = nlohmann::ordered_json;

[[noreturn]] void bad(const std::string& key, const std::string& what) {
    throw FormatError("result \"identification\"" + (key.empty() ? "" : ": \"" + key + "\"") + " " + what);
}
using IdentificationFields = fileio::JsonFields<ojson, decltype(&bad)>;

/// A number; null (what nlohmann writes for NaN and ±∞) reads as NaN.
double number_or_nan(const IdentificationFields& f, const char* key) {
    return f.at(key).is_null() ? std::numeric_limits<double>::quiet_NaN() : f.number(key);
}
int count(const IdentificationFields& f, const char* key) {
    return static_cast<int>(f.count(key));
}

}  // namespace

std::string identification_to_json(const ba::FitSummary& fit, const ErrorModel& model) {
    ojson j;
    j["converged"] = fit.converged;
    j["iterations"] = fit.iterations;
    j["message"] = fit.message.empty() ? ojson(nullptr) : ojson(fit.message);
    j["readings"] = fit.readings;
    j["degrees_of_freedom"] = fit.degrees_of_freedom;
    j["residual_rms_um"] = fit.residual_rms_mm * 1e3;
    j["residual_sigma_um"] = fit.residual_sigma_mm * 1e3;
    j["noise_floor_um"] = fit.noise_floor_mm * 1e3;
    j["uncertainty_from_noise_floor"] = fit.uncertainty_from_floor;
    j["initial_rms_um"] = fit.initial_rms_mm * 1e3;
    j["estimates"] = ojson::array();
    for (const auto& e : fit.estimates)
        j["estimates"].push_back(
            {{"name", e.name},
             {"unit", e.param ? std::string(ba::to_string(ba::param_info(*e.param).unit)) : std::string("mm")},
             {"value", e.estimate},
             {"value_std", e.std},
             {"sensitivity", e.sensitivity},
             {"independence", e.independence},
             {"observable", e.observable}});
    j["correlation"] = ojson::array();
    for (Eigen::Index r = 0; r < fit.correlation.rows(); ++r) {
        ojson row = ojson::array();
        for (Eigen::Index c = 0; c < fit.correlation.cols(); ++c) row.push_back(fit.correlation(r, c));
        j["correlation"].push_back(row);
    }
    j["correlation_names"] = ojson::array();
    for (std::size_t i : fit.fitted) j["correlation_names"].push_back(fit.estimates[i].name);
    j["model"] = ojson::parse(model_to_json(model));
    return j.dump();
}

IdentificationRecord identification_from_json(std::string_view text_in) {
    ojson j;
    try {
        j = ojson::parse(text_in);
    } catch (const ojson::exception& e) {
        throw FormatError(std::string("result \"identification\" is not valid JSON: ") + e.what());
    }
    const IdentificationFields f(j, "", &bad);
    f.only({"converged", "iterations", "message", "readings", "degrees_of_freedom", "residual_rms_um",
            "residual_sigma_um", "noise_floor_um", "uncertainty_from_noise_floor", "initial_rms_um", "estimates",
            "correlation", "correlation_names", "model"});
    IdentificationRecord r;
    r.converged = f.boolean("converged");
    r.residual_rms_um = f.number("residual_rms_um");
    (void)f.at("estimates");
    if (f.has("iterations")) r.iterations = count(f, "iterations");
    if (f.has("message") && !f.at("message").is_null()) r.message = f.text("message");
    if (f.has("readings")) r.readings = count(f, "readings");
    if (f.has("degrees_of_freedom")) r.degrees_of_freedom = count(f, "degrees_of_freedom");
    if (f.has("residual_sigma_um")) r.residual_sigma_um = f.number("residual_sigma_um");
    if (f.has("initial_rms_um")) r.initial_rms_um = f.number("initial_rms_um");
    if (f.has("noise_floor_um")) r.noise_floor_um = f.number("noise_floor_um");
    if (f.has("uncertainty_from_noise_floor"))
        r.uncertainty_from_noise_floor = f.boolean("uncertainty_from_noise_floor");
    if (!f.at("estimates").is_array()) bad("estimates", "must be an array");
    for (std::size_t i = 0; i < j["estimates"].size(); ++i) {
        const IdentificationFields e(j["estimates"][i], "estimates[" + std::to_string(i) + "]", &bad);
        // docs/cli.md's vocabulary (value, value_std), or as results were stored before it (estimate, std).
        const bool before_vocabulary = e.has("estimate");
        if (before_vocabulary)
            e.only({"name", "estimate", "std", "sensitivity", "independence", "observable", "unit"});
        else
            e.only({"name", "unit", "value", "value_std", "sensitivity", "independence", "observable"});
        IdentifiedEstimate x;
        x.name = e.text("name");
        x.estimate = e.number(before_vocabulary ? "estimate" : "value");
        x.std = number_or_nan(e, before_vocabulary ? "std" : "value_std");
        if (e.has("sensitivity")) x.sensitivity = number_or_nan(e, "sensitivity");
        if (e.has("independence")) x.independence = number_or_nan(e, "independence");
        x.observable = e.boolean("observable");
        x.unit = e.text("unit");
        r.estimates.push_back(std::move(x));
    }
    if (f.has("correlation_names")) {
        if (!j["correlation_names"].is_array()) bad("correlation_names", "must be an array of names");
        for (const auto& n : j["correlation_names"]) {
            if (!n.is_string()) bad("correlation_names", "must be an array of names");
            r.correlation_names.push_back(n.get<std::string>());
        }
    }
    if (f.has("correlation")) {
        const ojson& c = j["correlation"];
        if (!c.is_array() || c.size() != r.correlation_names.size())
            bad("correlation", "must be a square matrix over correlation_names");
        for (const auto& row : c) {
            if (!row.is_array() || row.size() != r.correlation_names.size())
                bad("correlation", "must be a square matrix over correlation_names");
            auto& out = r.correlation.emplace_back();
            for (const auto& v : row) {
                if (!v.is_null() && !v.is_number()) bad("correlation", "must hold numbers");
                out.push_back(v.is_null() ? std::numeric_limits<double>::quiet_NaN() : v.get<double>());
            }
        }
    }
    if (f.has("model")) {
        try {
            r.model = model_from_json(j["model"].dump());
        } catch (const FormatError& e) {
            bad("model", std::string("is not a model: ") + e.what());
        }
    }
    return r;
}

}  // namespace ballbar::storage
