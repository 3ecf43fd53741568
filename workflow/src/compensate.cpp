// SPDX-License-Identifier: MIT
#include "ballbar/workflow/compensate.hpp"

#include <algorithm>
#include <filesystem>
#include <optional>
#include <string>

#include "ballbar/analysis/nc_program.hpp"
#include "ballbar/fileio/input.hpp"
#include "ballbar/storage/machine_json.hpp"
#include "ballbar/storage/offsets_codec.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/workflow/error.hpp"

namespace ballbar::workflow {
namespace {

namespace ba = ballbar::analysis;
namespace bs = ballbar::storage;

ModelChoice parse_model(const std::string& text, const std::string& source) {
    try {
        return {bs::model_from_json(text), source};
    } catch (const bs::FormatError& e) {
        throw Error(ErrorCategory::bad_input, source + ": " + e.what());
    }
}

}  // namespace

ModelChoice find_model(const std::string& spec, const std::string& db_path, std::string_view db_hint) {
    namespace fs = std::filesystem;
    std::error_code ec;
    // Anything at that path is a file to read (fileio says when it is a directory or a FIFO).
    if (fs::exists(fs::symlink_status(spec, ec))) {
        std::string text;
        try {
            text = fileio::read_json(spec, "model");
        } catch (const fileio::FileError& e) {
            throw Error(category_of(e), e.what());
        }
        return parse_model(text, spec);
    }
    if (!fs::exists(db_path, ec))  // a model id or name is looked up in an existing database only
        throw Error(ErrorCategory::bad_input, "model '" + spec + "': no such file, and no database at " + db_path +
                                                  " for a model id or name" + std::string(db_hint));
    bs::Store store(db_path);
    const bool numeric =
        !spec.empty() && std::all_of(spec.begin(), spec.end(), [](char c) { return c >= '0' && c <= '9'; });
    try {
        if (numeric) return parse_model(store.model(std::stoll(spec)).params_json, "model " + spec);
        if (const auto r = store.latest_model(spec))
            return parse_model(r->params_json, "model " + r->name + " v" + std::to_string(r->version));
    } catch (const bs::StorageError& e) {
        throw Error(ErrorCategory::bad_input, e.what());  // "no model 99", said once
    } catch (const std::out_of_range&) {                  // more digits than an id has
        throw Error(ErrorCategory::bad_input, "no model " + spec);
    }
    throw Error(ErrorCategory::bad_input, "model '" + spec + "': no such file, model id or model name");
}

ba::NcDialect program_dialect(const ProgramCompensation& settings, const std::string& program_name) {
    if (!settings.dialect.empty()) {
        const auto d = ba::parse_nc_dialect(settings.dialect);
        if (!d) throw Error(ErrorCategory::bad_input, "--dialect: '" + settings.dialect + "' (fanuc or linuxcnc)");
        return *d;
    }
    return std::filesystem::path(program_name).extension() == ".ngc" ? ba::NcDialect::LinuxCNC : ba::NcDialect::Fanuc;
}

ba::NcCompensateSummary compensate_program(const ModelChoice& model, std::string_view text,
                                           const std::string& program_name, const ProgramCompensation& settings,
                                           const ba::NcSink& sink) {
    ba::NcInterpreterOptions io = settings.interpreter;
    io.dialect = program_dialect(settings, program_name);
    if (!settings.offsets_json.empty()) {
        try {
            io.offsets = bs::offsets_from_json(settings.offsets_json);
        } catch (const bs::FormatError& e) {
            throw Error(ErrorCategory::bad_input, settings.offsets_source + ": " + e.what());
        }
        io.have_offsets = true;
    }
    const std::string controller = !settings.controller.empty()            ? settings.controller
                                   : io.dialect == ba::NcDialect::LinuxCNC ? "linuxcnc"
                                                                           : "fanuc";
    const auto codes = ba::tcp_codes_for(controller);
    if (!codes)
        throw Error(ErrorCategory::bad_input,
                    "--controller: '" + controller + "' (linuxcnc, fanuc, siemens, heidenhain, none)");
    io.tcp = *codes;
    if (!settings.tcp_on.empty()) io.tcp.on = settings.tcp_on;
    if (!settings.tcp_off.empty()) io.tcp.off = settings.tcp_off;

    ba::NcCompensateOptions co = settings.options;
    co.empirical = model.model.empirical;  // terms learned by discover (angular tables, positioning errors)
    co.title = "compensated by ballbar with " + model.source;
    try {
        return ba::compensate_nc_program(text, model.model.machine, model.model.values(), io, co, sink);
    } catch (const ba::NcError& e) {
        throw Error(ErrorCategory::bad_input, program_name + ": " + e.what());
    } catch (const ba::AnalysisError& e) {
        throw Error(ErrorCategory::bad_input, program_name + ": " + e.what());
    }
}

}  // namespace ballbar::workflow
