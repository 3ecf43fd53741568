// SPDX-License-Identifier: MIT
#include "ballbar/acquisition/result_codec.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>

namespace ballbar::acquisition {
namespace {

using json = nlohmann::ordered_json;

json vec(const analysis::Vec3& v) {
    return json::array({v.x(), v.y(), v.z()});
}

json angles(const std::optional<analysis::OrientationErrors>& e) {
    if (!e) return nullptr;
    return {{"d_alpha_rad", e->d_alpha_rad}, {"d_beta_rad", e->d_beta_rad}, {"d_gamma_rad", e->d_gamma_rad}};
}

/// Reads one payload of `kind`, naming it in every message.
class Reader {
  public:
    Reader(std::string_view kind, std::string_view text, std::initializer_list<std::string_view> keys) : kind_(kind) {
        try {
            j_ = json::parse(text);
        } catch (const json::exception& e) {
            fail("", std::string("is not valid JSON: ") + e.what());
        }
        if (!j_.is_object()) fail("", "is not a JSON object");
        for (const auto& item : j_.items())
            if (std::find(keys.begin(), keys.end(), item.key()) == keys.end()) fail(item.key(), "is not a key it has");
    }
    const json& root() const { return j_; }

    [[noreturn]] void fail(const std::string& key, const std::string& what) const {
        throw ResultFormatError("result \"" + kind_ + "\"" + (key.empty() ? "" : ": \"" + key + "\"") + " " + what);
    }
    const json& at(const json& j, const std::string& key) const {
        const auto it = j.find(key);
        if (it == j.end()) fail(key, "is missing");
        return *it;
    }
    double number(const json& v, const std::string& key) const {
        if (!v.is_number() || !std::isfinite(v.get<double>())) fail(key, "must be a finite number");
        return v.get<double>();
    }
    int count(const json& v, const std::string& key, int lo = 0) const {
        if (!v.is_number_integer() || v.get<std::int64_t>() < lo || v.get<std::int64_t>() > 1'000'000'000)
            fail(key, "must be an integer of at least " + std::to_string(lo));
        return v.get<int>();
    }
    analysis::Vec3 vec3(const json& v, const std::string& key) const {
        if (!v.is_array() || v.size() != 3) fail(key, "must be an array of three numbers");
        return {number(v[0], key), number(v[1], key), number(v[2], key)};
    }
    std::optional<analysis::OrientationErrors> angles(const json& v, const std::string& key) const {
        if (v.is_null()) return std::nullopt;
        if (!v.is_object() || v.size() != 3) fail(key, "must be null or {d_alpha_rad, d_beta_rad, d_gamma_rad}");
        return analysis::OrientationErrors{number(at(v, "d_alpha_rad"), key + ".d_alpha_rad"),
                                           number(at(v, "d_beta_rad"), key + ".d_beta_rad"),
                                           number(at(v, "d_gamma_rad"), key + ".d_gamma_rad")};
    }

  private:
    std::string kind_;
    json j_;
};

TestKind test_kind(const Reader& r, const json& v) {
    for (TestKind k : {TestKind::BothAxes, TestKind::SpindleBeta, TestKind::TableAlpha})
        if (v.is_string() && v.get<std::string>() == to_string(k)) return k;
    r.fail("kind", "must be \"BothAxes\", \"SpindleBeta\" or \"TableAlpha\"");
}

}  // namespace

std::string location_to_json(const LocationResult& r) {
    json j;
    j["test"] = r.test;
    j["step"] = r.step;
    j["datum_mm"] = vec(r.datum_mm);
    j["e_exact_mm"] = vec(r.ssm.exact_mm);
    j["e_linear_mm"] = vec(r.ssm.linear_mm);
    j["e_std_mm"] = vec(r.ssm.std_mm);
    j["dV_mm"] = vec(r.dV_mm);
    // +∞ for a degenerate layout: JSON has no infinity, null says it
    j["condition_number"] = std::isfinite(r.ssm.condition_number) ? json(r.ssm.condition_number) : json(nullptr);
    j["n"] = r.ssm.n;
    if (r.ssm.residual_rms_mm) j["residual_rms_mm"] = *r.ssm.residual_rms_mm;
    return j.dump();
}

LocationResult location_from_json(std::string_view text) {
    const Reader rd(kSsmResultKind, text,
                    {"test", "step", "datum_mm", "e_exact_mm", "e_linear_mm", "e_std_mm", "dV_mm", "condition_number",
                     "n", "residual_rms_mm"});
    const json& j = rd.root();
    LocationResult r;
    r.test = rd.count(rd.at(j, "test"), "test");
    r.step = rd.count(rd.at(j, "step"), "step", 1);
    if (r.step > 2) rd.fail("step", "must be 1 or 2");
    r.datum_mm = rd.vec3(rd.at(j, "datum_mm"), "datum_mm");
    r.ssm.exact_mm = rd.vec3(rd.at(j, "e_exact_mm"), "e_exact_mm");
    r.ssm.linear_mm = rd.vec3(rd.at(j, "e_linear_mm"), "e_linear_mm");
    r.ssm.std_mm = rd.vec3(rd.at(j, "e_std_mm"), "e_std_mm");
    for (int a = 0; a < 3; ++a)
        if (r.ssm.std_mm[a] < 0) rd.fail("e_std_mm", "cannot be negative");
    r.dV_mm = rd.vec3(rd.at(j, "dV_mm"), "dV_mm");
    const json& cond = rd.at(j, "condition_number");
    r.ssm.condition_number =
        cond.is_null() ? std::numeric_limits<double>::infinity() : rd.number(cond, "condition_number");
    r.ssm.n = static_cast<std::size_t>(rd.count(rd.at(j, "n"), "n"));
    if (const auto it = j.find("residual_rms_mm"); it != j.end())
        r.ssm.residual_rms_mm = rd.number(*it, "residual_rms_mm");
    return r;
}

std::string test_to_json(const TestResult& r) {
    json j;
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
    const Reader rd(kOrientationResultKind, text,
                    {"test", "kind", "dV1_mm", "dV2_mm", "first_order", "exact", "std", "singular"});
    const json& j = rd.root();
    TestResult r;
    r.test = rd.count(rd.at(j, "test"), "test");
    r.kind = test_kind(rd, rd.at(j, "kind"));
    r.dV1_mm = rd.vec3(rd.at(j, "dV1_mm"), "dV1_mm");
    r.dV2_mm = rd.vec3(rd.at(j, "dV2_mm"), "dV2_mm");
    r.orientation.first_order = rd.angles(rd.at(j, "first_order"), "first_order");
    r.orientation.exact = rd.angles(rd.at(j, "exact"), "exact");
    r.std_rad = rd.angles(rd.at(j, "std"), "std");
    if (const auto it = j.find("singular"); it != j.end()) {
        if (!it->is_string()) rd.fail("singular", "must be a string");
        r.orientation.singular = it->get<std::string>();
    }
    return r;
}

std::string plan_to_json(const Plan& plan) {
    json j;
    j["machine"] = json::parse(write_machine_file(plan.machine));
    j["plan"] = json::parse(write_plan_file(plan.spec, plan.machine.geometry.type));
    return j.dump();
}

Plan plan_from_json(std::string_view text) {
    const Reader rd(kPlanResultKind, text, {"machine", "plan"});
    // The files' own readers check them (PlanError names what is wrong).
    const MachineFile m = parse_machine_file(rd.at(rd.root(), "machine").dump());
    return make_plan(m, parse_plan_file(rd.at(rd.root(), "plan").dump(), m.geometry.type));
}

}  // namespace ballbar::acquisition
