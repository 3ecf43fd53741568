// SPDX-License-Identifier: MIT
#include "ballbar/acquisition/result_codec.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>

#include "ballbar/fileio/json_fields.hpp"

namespace ballbar::acquisition {
namespace {

using ojson = nlohmann::ordered_json;

ojson vec(const analysis::Vec3& v) {
    return ojson::array({v.x(), v.y(), v.z()});
}

ojson angles(const std::optional<analysis::OrientationErrors>& e) {
    if (!e) return nullptr;
    return {{"d_alpha_rad", e->d_alpha_rad}, {"d_beta_rad", e->d_beta_rad}, {"d_gamma_rad", e->d_gamma_rad}};
}

/// Parses one payload of `kind`; every error names the kind and the key.
ojson parse(std::string_view kind, std::string_view text) {
    try {
        return ojson::parse(text);
    } catch (const ojson::exception& e) {
        throw ResultFormatError("result \"" + std::string(kind) + "\" is not valid JSON: " + e.what());
    }
}

auto failing(std::string_view kind) {
    return [kind = std::string(kind)](const std::string& key, const std::string& problem) {
        throw ResultFormatError("result \"" + kind + "\"" + (key.empty() ? "" : ": \"" + key + "\"") + " " + problem);
    };
}
using Fields = fileio::JsonFields<ojson, decltype(failing(""))>;

int count(const Fields& f, const char* key, int lo = 0) {
    const auto v = f.count(key, 1'000'000'000);
    if (v < lo) f.refuse(key, "must be an integer of at least " + std::to_string(lo));
    return static_cast<int>(v);
}

std::optional<analysis::OrientationErrors> angles(const Fields& f, const char* key) {
    const ojson& v = f.at(key);
    if (v.is_null()) return std::nullopt;
    if (!v.is_object() || v.size() != 3) f.refuse(key, "must be null or {d_alpha_rad, d_beta_rad, d_gamma_rad}");
    const Fields a(v, f.path(key), f.fail());
    return analysis::OrientationErrors{a.number("d_alpha_rad"), a.number("d_beta_rad"), a.number("d_gamma_rad")};
}

TestKind test_kind(const Fields& f) {
    const ojson& v = f.at("kind");
    for (TestKind k : {TestKind::BothAxes, TestKind::SpindleBeta, TestKind::TableAlpha})
        if (v.is_string() && v.get<std::string>() == to_string(k)) return k;
    f.refuse("kind", "must be \"BothAxes\", \"SpindleBeta\" or \"TableAlpha\"");
}

}  // namespace

std::string location_to_json(const LocationResult& r) {
    ojson j;
    j["test"] = r.test;
    j["step"] = r.step;
    j["datum_mm"] = vec(r.datum_mm);
    j["e_exact_mm"] = vec(r.ssm.exact_mm);
    j["e_linear_mm"] = vec(r.ssm.linear_mm);
    j["e_std_mm"] = vec(r.ssm.std_mm);
    j["dV_mm"] = vec(r.dV_mm);
    // +∞ for a degenerate layout: JSON has no infinity, null says it
    j["condition_number"] = std::isfinite(r.ssm.condition_number) ? ojson(r.ssm.condition_number) : ojson(nullptr);
    j["n"] = r.ssm.n;
    if (r.ssm.residual_rms_mm) j["residual_rms_mm"] = *r.ssm.residual_rms_mm;
    return j.dump();
}

LocationResult location_from_json(std::string_view text) {
    const ojson j = parse(kSsmResultKind, text);
    const Fields f(j, "", failing(kSsmResultKind));
    f.only({"test", "step", "datum_mm", "e_exact_mm", "e_linear_mm", "e_std_mm", "dV_mm", "condition_number", "n",
            "residual_rms_mm"});
    LocationResult r;
    r.test = count(f, "test");
    r.step = count(f, "step", 1);
    if (r.step > 2) f.refuse("step", "must be 1 or 2");
    r.datum_mm = f.vec3<analysis::Vec3>("datum_mm");
    r.ssm.exact_mm = f.vec3<analysis::Vec3>("e_exact_mm");
    r.ssm.linear_mm = f.vec3<analysis::Vec3>("e_linear_mm");
    r.ssm.std_mm = f.vec3<analysis::Vec3>("e_std_mm");
    if (r.ssm.std_mm.minCoeff() < 0) f.refuse("e_std_mm", "cannot be negative");
    r.dV_mm = f.vec3<analysis::Vec3>("dV_mm");
    // +∞ for a degenerate layout: null
    r.ssm.condition_number =
        f.at("condition_number").is_null() ? std::numeric_limits<double>::infinity() : f.number("condition_number");
    r.ssm.n = static_cast<std::size_t>(count(f, "n"));
    if (f.has("residual_rms_mm")) r.ssm.residual_rms_mm = f.number("residual_rms_mm");
    return r;
}

std::string test_to_json(const TestResult& r) {
    ojson j;
    j["test"] = r.test;
    j["kind"] = std::string(to_string(r.kind));
    j["dV1_mm"] = vec(r.dV1_mm);
    j["dV2_mm"] = vec(r.dV2_mm);
    j["first_order"] = angles(r.orientation.first_order);
    j["exact"] = angles(r.orientation.exact);
    j["std"] = angles(r.std_rad);  // of the exact solution
    if (!r.orientation.singular.empty()) j["singular"] = r.orientation.singular;
    return j.dump();
}

TestResult test_from_json(std::string_view text) {
    const ojson j = parse(kOrientationResultKind, text);
    const Fields f(j, "", failing(kOrientationResultKind));
    f.only({"test", "kind", "dV1_mm", "dV2_mm", "first_order", "exact", "std", "singular"});
    TestResult r;
    r.test = count(f, "test");
    r.kind = test_kind(f);
    r.dV1_mm = f.vec3<analysis::Vec3>("dV1_mm");
    r.dV2_mm = f.vec3<analysis::Vec3>("dV2_mm");
    r.orientation.first_order = angles(f, "first_order");
    r.orientation.exact = angles(f, "exact");
    r.std_rad = angles(f, "std");
    if (f.has("singular")) r.orientation.singular = f.text("singular");
    return r;
}

std::string plan_to_json(const Plan& plan) {
    ojson j;
    j["machine"] = ojson::parse(write_machine_file(plan.machine));
    j["plan"] = ojson::parse(write_plan_file(plan.spec, plan.machine.geometry.type));
    return j.dump();
}

Plan plan_from_json(std::string_view text) {
    const ojson j = parse(kPlanResultKind, text);
    const Fields f(j, "", failing(kPlanResultKind));
    f.only({"machine", "plan"});
    // The files' own readers check them (PlanError names what is wrong).
    const MachineFile m = parse_machine_file(f.at("machine").dump());
    return make_plan(m, parse_plan_file(f.at("plan").dump(), m.geometry.type));
}

}  // namespace ballbar::acquisition
