// SPDX-License-Identifier: MIT
#include "ballbar/storage/compensation_codec.hpp"

#include <nlohmann/json.hpp>

#include "ballbar/fileio/json_fields.hpp"
#include "ballbar/storage/machine_json.hpp"

namespace ballbar::storage {
namespace {

[[noreturn]] void bad_compensation(const std::string& key, const std::string& what) {
    throw FormatError("result \"compensation\"" + (key.empty() ? "" : ": \"" + key + "\"") + " " + what);
}
using CompensationFields = fileio::JsonFields<nlohmann::ordered_json, decltype(&bad_compensation)>;

}  // namespace

std::string compensation_to_json(const CompensationRecord& record) {
    nlohmann::ordered_json j;
    j["metric"] = record.metric;
    j["axes"] = nlohmann::ordered_json::array();
    for (const auto& a : record.axes)
        j["axes"].push_back({{"axis", a.axis}, {"before_um", a.before_um}, {"after_um", a.after_um}});
    return j.dump();
}

CompensationRecord compensation_from_json(std::string_view text) {
    const auto j = nlohmann::ordered_json::parse(text, nullptr, false);
    if (j.is_discarded()) bad_compensation("", "is not JSON");
    const CompensationFields f(j, "", &bad_compensation);
    f.only({"metric", "axes"});
    CompensationRecord r;
    r.metric = f.text("metric");
    const auto& axes = f.at("axes");
    if (!axes.is_array()) bad_compensation("axes", "must be an array");
    for (std::size_t i = 0; i < axes.size(); ++i) {
        const CompensationFields a(axes[i], "axes[" + std::to_string(i) + "]", &bad_compensation);
        CompensationRecord::Axis x;
        x.axis = a.text("axis");
        if (a.has("unit")) {  // before the vocabulary: {"axis", "unit": "µm", "before", "after"}
            a.only({"axis", "unit", "before", "after"});
            const std::string unit = a.text("unit");
            if (unit != "µm" && unit != "um") a.refuse("unit", "must be µm");
            x.before_um = a.number("before");
            x.after_um = a.number("after");
        } else {
            a.only({"axis", "before_um", "after_um"});
            x.before_um = a.number("before_um");
            x.after_um = a.number("after_um");
        }
        r.axes.push_back(x);
    }
    return r;
}

}  // namespace ballbar::storage
