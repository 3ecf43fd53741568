// SPDX-License-Identifier: MIT
// `ballbar discover SESSION|FILE... [--model MODEL] [--json]`: the discovery workflow (docs/discovery.md)
// on the readings of stored sessions and/or readings files. Prints a table (or, with --json, the
// result as JSON); with sessions among the inputs, stores the result with each session and the
// extended model, one version per step, in the models table.
#include <malloc.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ballbar/analysis/discovery.hpp"
#include "ballbar/analysis/effects.hpp"
#include "ballbar/analysis/identify.hpp"
#include "ballbar/storage/model_codec.hpp"
#include "ballbar/storage/readings.hpp"
#include "ballbar/storage/readings_file.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/workflow/discover.hpp"
#include "ballbar/workflow/identify.hpp"
#include "command.hpp"

namespace ballbar::app {
namespace {

namespace ba = ballbar::analysis;

struct DiscoverOptions {
    std::vector<std::string> inputs;
    std::string model;
    std::string save_model;
    std::optional<double> noise_um;
    bool json = false;
};

using Inputs = workflow::ReadingInputs;

std::string format_value(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
}

void print_table(const ba::DiscoveryResult& r, const ba::ReadingSet& set, const std::vector<std::string>& inputs) {
    std::printf("discovery: %s machine%s%s, %zu readings from %zu input(s)\n",
                std::string(ba::to_string(r.type)).c_str(), set.machine.name.empty() ? "" : " ",
                set.machine.name.c_str(), set.readings.size(), inputs.size());
    std::printf("base model:");
    for (ba::Param p : r.base_model) std::printf(" %s", std::string(ba::param_info(p).name).c_str());
    std::printf(" + socket offsets\n");
    std::printf("initial residual RMS %.3f µm (best explained by %s)\n\n", r.rms_initial_mm * 1e3,
                std::string(ba::to_string(r.initial_residuals.best, r.type)).c_str());
    if (r.noise_floor.known())
        std::printf("noise floor %.3f µm (%s: %s)\n", r.noise_floor.sigma_mm * 1e3, r.noise_floor.source.c_str(),
                    r.noise_floor.detail.c_str());
    else
        std::printf("noise floor unknown (%s)\n", r.noise_floor.detail.c_str());
    if (r.steps.empty()) {
        std::printf("no effect of the library passes the criterion\n");
    } else {
        std::printf("%-4s %-24s %-5s %14s %10s %-6s %21s %10s  %s\n", "step", "effect", "ISO", "estimate", "std",
                    "unit", "RMS before -> after", "F", "explained by");
        int i = 1;
        for (const ba::DiscoveryStep& st : r.steps)
            std::printf("%-4d %-24s %-5s %14s %10s %-6s %9.3f → %6.3f µm %10.1f  %s%s\n", i++,
                        std::string(st.effect->id).c_str(), std::string(st.effect->iso).c_str(),
                        format_value(st.estimate).c_str(), format_value(st.std_error).c_str(),
                        std::string(ba::to_string(st.effect->unit())).c_str(), st.rms_before_mm * 1e3,
                        st.rms_after_mm * 1e3, st.value, std::string(ba::to_string(st.explained_by, r.type)).c_str(),
                        st.withdrawn ? "  (withdrawn: not significant given the learned terms)" : "");
    }
    auto verdict_line = [](const char* when, const ba::NoiseVerdict& v) {
        if (!v.floor_known) {
            std::printf(
                "%s: residual RMS %.3f µm; the noise floor is unknown, so whether it is noise cannot be "
                "decided (give --noise-um)\n",
                when, v.rms_mm * 1e3);
            return;
        }
        std::printf("%s: residual RMS %.3f µm = %.2fx the noise floor: %s (chi-square %.1f on %.0f dof, p = %.3g%s)\n",
                    when, v.rms_mm * 1e3, v.ratio, v.structure ? "UNEXPLAINED STRUCTURE" : "consistent with noise",
                    v.chi2, v.dof, v.p_value, v.structure ? ", below the threshold" : "");
    };
    verdict_line("\nbefore the search beyond the library", r.verdict_library);
    for (const ba::EmpiricalStep& st : r.learned) {
        std::printf("\nbeyond the library: %s\n", st.description.c_str());
        std::printf("  found in %s (family %s): F = %.1f on (%.0f, %.0f) dof, p = %.3g < %.3g; RMS %.3f -> %.3f µm\n",
                    st.variable.c_str(), st.family.c_str(), st.f, st.dof1, st.dof2, st.p_value, st.threshold_p,
                    st.rms_before_mm * 1e3, st.rms_after_mm * 1e3);
        for (const ba::LearnedTerm& t : st.terms)
            std::printf("  learned %-22s %12s +- %-10s %s\n", t.term.name().c_str(), format_value(t.value).c_str(),
                        format_value(t.std_error).c_str(), t.term.unit().c_str());
        if (st.families.size() > 1)
            std::printf("  next best: %s (F = %.1f)\n", st.families[1].family.c_str(), st.families[1].f);
    }
    if (!r.unlocated.empty()) std::printf("\nunexplained structure not located: %s\n", r.unlocated.c_str());
    verdict_line("\nfinal", r.verdict);
    std::printf("final residual RMS %.3f µm\n", r.rms_final_mm * 1e3);
    for (const auto& g : r.confounded) {
        std::printf("confounded (the readings cannot tell these apart):");
        for (const auto& n : g) std::printf(" %s", n.c_str());
        std::printf("\n");
    }
    if (!r.unidentifiable.empty()) {
        std::printf("not determined by these readings (left out):");
        for (const auto& n : r.unidentifiable) std::printf(" %s", n.c_str());
        std::printf("\n");
    }
    std::printf("criterion: %s\n", r.criterion_text.c_str());
}

int run_discover(const DiscoverOptions& o, const Globals& globals) {
    // The workflow allocates matrices of ~40 MB (100,000 readings × 50 columns) again and again: above
    // glibc's largest automatic mmap threshold (32 MB) each would be mapped, faulted in page by page and
    // unmapped. Kept in the heap, freed blocks are reused (half the page faults of a 100,800-reading run).
    mallopt(M_MMAP_THRESHOLD, 512 << 20);
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
    std::unique_ptr<storage::Store> store;
    // Sessions are read from an existing database only (a mistyped --db is not a new file).
    const workflow::StoreOpener open = [&]() -> storage::Store& {
        if (!store) store = std::make_unique<storage::Store>(existing_db_path(globals));
        return *store;
    };
    Inputs in = workflow::read_inputs(o.inputs, open);
    workflow::DiscoverOptions dopt;
    dopt.noise_um = o.noise_um;
    dopt.model = o.model;
    dopt.save_model = o.save_model;
    const workflow::DiscoverResult d = workflow::discover(std::move(in), dopt, store ? open : workflow::StoreOpener{});
    if (o.json)
        std::cout << workflow::discovery_json(d.result) << std::endl;
    else
        print_table(d.result, d.readings, d.input_names);
    return kExitOk;
}

}  // namespace
}  // namespace ballbar::app

BALLBAR_COMMAND(discover) {
    using namespace ballbar::app;
    auto opts = std::make_shared<DiscoverOptions>();
    auto* sub = root.add_subcommand(
        "discover",
        "Find where the model and the readings disagree, name the missing effects, refit (docs/discovery.md)");
    sub->add_option("inputs", opts->inputs, "Readings files (ballbar-readings/1) and/or session ids")->required();
    sub->add_option("--model", opts->model,
                    "Model to start from: comma-separated parameters or effect ids, 'base' for the rotary location "
                    "errors and zero offsets (default)");
    sub->add_option("--save-model", opts->save_model,
                    "Name of the extended model stored with the sessions (default <machine>-discovered)");
    sub->add_option("--noise-um", opts->noise_um,
                    "Noise of one reading in µm (default: from the readings' n/std_mm or repeated points)")
        ->check(in_range(0, 1000, "µm", true));
    sub->add_flag("--json", opts->json, "Print the result as JSON");
    sub->callback([opts, &globals] { globals.action = [opts, &globals] { return run_discover(*opts, globals); }; });
}
