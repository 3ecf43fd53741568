// SPDX-License-Identifier: MIT
// `ballbar compensate --model MODEL --program IN.nc --out OUT.nc [--dialect D] [--exact] [--json]`:
// rewrites an NC program so that, on the machine described by the identified model, the tool ball
// lands where the program meant it relative to the table (compensate.hpp). MODEL is a
// `ballbar-model/1` JSON file (what `ballbar identify` stores), a model id in the database, or a model
// name (its latest version). Reports the largest correction and the blocks near a singularity.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/analysis/compensate.hpp"
#include "ballbar/analysis/nc_program.hpp"
#include "ballbar/storage/machine_json.hpp"
#include "ballbar/storage/store.hpp"
#include "command.hpp"

namespace ballbar::app {
namespace {

namespace ba = ballbar::analysis;
namespace bs = ballbar::storage;
using nlohmann::json;

struct CompensateArgs {
    std::string model;
    std::string program;
    std::string out;
    std::string dialect;
    bool exact = false;
    bool json = false;
    double singular_deg = 0.06;
};

struct Model {
    ba::MachineGeometry machine;
    ba::ErrorParams params{};
    std::vector<ba::LearnedTerm> empirical;  ///< learned by discovery (docs/discovery.md)
    std::string source;
};

Model parse_model(const std::string& text, const std::string& source) {
    json j;
    try {
        j = json::parse(text);
    } catch (const json::parse_error& e) {
        throw CliError(kExitUsage, source + ": malformed JSON: " + e.what());
    }
    if (!j.is_object()) throw CliError(kExitUsage, source + ": a model must be a JSON object");
    if (j.contains("format") && j["format"] != "ballbar-model/1")
        throw CliError(kExitUsage, source + ": format " + j["format"].dump() + " is not ballbar-model/1");
    if (!j.contains("machine")) throw CliError(kExitUsage, source + ": no \"machine\" (the geometry is needed)");
    Model m;
    m.source = source;
    try {
        m.machine = bs::machine_from_json(j["machine"].dump());
    } catch (const std::exception& e) {
        throw CliError(kExitUsage, source + ": machine: " + e.what());
    }
    if (!j.contains("params") || !j["params"].is_object())
        throw CliError(kExitUsage, source + ": \"params\" must be an object {\"X0C\": value, ...}");
    for (const auto& item : j["params"].items()) {
        const auto p = ba::parse_param(item.key());
        if (!p) throw CliError(kExitUsage, source + ": params." + item.key() + ": unknown parameter");
        if (!item.value().is_number() || !std::isfinite(item.value().get<double>()))
            throw CliError(kExitUsage, source + ": params." + item.key() + ": must be a finite number");
        m.params[*p] = item.value().get<double>();
    }
    if (j.contains("empirical")) {  // terms learned by `discover`: angular error tables, positioning errors
        if (!j["empirical"].is_object())
            throw CliError(kExitUsage, source + ": \"empirical\" must be an object {\"C_angular_h1_cos\": value, ...}");
        for (const auto& item : j["empirical"].items()) {
            const auto t = ba::parse_empirical_term(item.key());
            if (!t) throw CliError(kExitUsage, source + ": empirical." + item.key() + ": unknown term");
            if (!item.value().is_number() || !std::isfinite(item.value().get<double>()))
                throw CliError(kExitUsage, source + ": empirical." + item.key() + ": must be a finite number");
            m.empirical.push_back({*t, item.value().get<double>(), 0.0});
        }
    }
    return m;
}

Model load_model(const std::string& spec, const Globals& globals) {
    std::error_code ec;
    if (std::filesystem::is_regular_file(spec, ec)) return parse_model(read_file(spec, "model"), spec);
    bs::Store store(resolve_db_path(globals));
    const bool numeric =
        !spec.empty() && std::all_of(spec.begin(), spec.end(), [](char c) { return c >= '0' && c <= '9'; });
    try {
        if (numeric) {
            const bs::ModelRecord r = store.model(std::stoll(spec));
            return parse_model(r.params_json, "model " + spec);
        }
        if (const auto r = store.latest_model(spec))
            return parse_model(r->params_json, "model " + r->name + " v" + std::to_string(r->version));
    } catch (const bs::StorageError& e) {
        throw CliError(kExitUsage, "model " + spec + ": " + e.what());
    }
    throw CliError(kExitUsage, "model '" + spec + "': no such file, model id or model name");
}

ba::NcDialect pick_dialect(const CompensateArgs& args) {
    if (!args.dialect.empty()) {
        const auto d = ba::parse_nc_dialect(args.dialect);
        if (!d) throw CliError(kExitUsage, "--dialect: '" + args.dialect + "' (fanuc or linuxcnc)");
        return *d;
    }
    const std::string ext = std::filesystem::path(args.program).extension().string();
    return ext == ".ngc" ? ba::NcDialect::LinuxCNC : ba::NcDialect::Fanuc;
}

/// Where the compensated program goes. "-" or /dev/stdout (or a path to what stdout is): standard
/// output itself, so the program and nothing else lands there (the caller prints its summary on
/// stderr then). A regular file (new or not) is written as OUT.part beside it and renamed over it by
/// commit(), keeping its permissions; until then the destructor removes the .part, so a program with
/// an error, a full disk or any exception leaves OUT as it was. A symlink is followed. Anything else
/// that exists (a FIFO, a device) and any path under /dev or /proc is written directly. A directory
/// is refused before any work.
class OutputFile {
  public:
    explicit OutputFile(const std::string& name) : name_(name), target_(name) {
        namespace fs = std::filesystem;
        std::error_code ec;
        if (name == "-" || (fs::equivalent(target_, "/dev/stdout", ec) && !ec)) {
            stdout_ = true;
            os_ = &std::cout;
            return;
        }
        const fs::file_status st = fs::status(target_, ec);  // through symlinks
        if (fs::is_directory(st)) throw CliError(kExitUsage, "--out " + name_ + " is a directory");
        // Device and process files (/dev/stderr, /proc/self/fd/N) are never renamed over.
        auto system_file = [](const fs::path& p) {
            const std::string s = p.string();
            return s.rfind("/dev/", 0) == 0 || s.rfind("/proc/", 0) == 0;
        };
        direct_ =
            (fs::exists(st) && !fs::is_regular_file(st)) || system_file(fs::absolute(target_, ec).lexically_normal());
        if (!direct_ && fs::is_symlink(fs::symlink_status(target_, ec))) {
            const fs::path real = fs::canonical(target_, ec);  // replace the file, keep the link
            if (ec || system_file(real))
                direct_ = true;
            else
                target_ = real;
        }
        path_ = target_;
        if (!direct_) path_ += ".part";
        file_.open(path_, std::ios::binary | std::ios::trunc);
        if (!file_) throw CliError(kExitFailure, "cannot write " + path_.string());
        os_ = &file_;
    }
    ~OutputFile() {
        if (committed_ || direct_ || stdout_ || !file_.is_open()) return;
        file_.close();
        std::error_code ec;
        std::filesystem::remove(path_, ec);
    }
    OutputFile(const OutputFile&) = delete;
    OutputFile& operator=(const OutputFile&) = delete;

    /// The program goes to standard output: the summary must not.
    bool is_stdout() const { return stdout_; }
    void write(std::string_view text) {
        os_->write(text.data(), static_cast<std::streamsize>(text.size()));
        if (!*os_) throw CliError(kExitFailure, "write failed: " + name_);
    }
    void commit() {
        if (stdout_) {
            std::cout.flush();
            if (!std::cout) throw CliError(kExitFailure, "write failed: " + name_);
            return;
        }
        file_.close();
        if (!file_) throw CliError(kExitFailure, "write failed: " + name_);
        if (direct_) return;
        namespace fs = std::filesystem;
        std::error_code ec;
        if (fs::is_regular_file(target_, ec)) fs::permissions(path_, fs::status(target_, ec).permissions(), ec);
        fs::rename(path_, target_, ec);
        if (ec) throw CliError(kExitFailure, "cannot write " + name_ + ": " + ec.message());
        committed_ = true;
    }

  private:
    std::string name_;
    std::filesystem::path target_, path_;
    std::ofstream file_;
    std::ostream* os_ = nullptr;
    bool stdout_ = false, direct_ = false, committed_ = false;
};

int run_compensate(const CompensateArgs& args, const Globals& globals) {
    const Model model = load_model(args.model, globals);
    const ba::NcDialect dialect = pick_dialect(args);
    const std::string text = read_file(args.program, "program");
    ba::CompensationOptions co;
    co.singular_tolerance = std::sin(ba::deg_to_rad(args.singular_deg));
    const ba::Compensator comp(model.machine, model.params, model.empirical, co);
    const bool second_is_c = ba::rotary_axes(model.machine.type).second == 'C';

    // Streams: one block is parsed, compensated and written at a time, in 1 MiB chunks.
    OutputFile out(args.out);
    std::string chunk;
    constexpr std::size_t kChunkBytes = 1 << 20;
    chunk.reserve(kChunkBytes + 4096);
    auto flush = [&] {
        out.write(chunk);
        chunk.clear();
    };

    std::size_t blocks = 0;
    std::size_t compensated = 0;
    double max_linear = 0, max_rotary = 0;
    int max_linear_line = 0, max_rotary_line = 0;
    std::vector<int> singular_lines;
    std::size_t singular_count = 0;
    ba::write_nc_header(chunk, dialect, "compensated by ballbar with " + model.source);
    try {
        ba::NcReader reader(text, dialect);
        ba::NcBlock b;
        ba::Pose pose;  // modal: the absolute commanded pose after each block
        while (reader.next(b)) {
            ++blocks;
            pose = ba::pose_after(b, pose);
            if (b.motion == ba::NcMotion::Rapid || b.motion == ba::NcMotion::Feed) {
                const ba::Correction c = args.exact ? comp.exact(pose) : comp.first_order(pose);
                const double lin = std::sqrt(c.du[0] * c.du[0] + c.du[1] * c.du[1] + c.du[2] * c.du[2]);
                const double rot = std::max(std::abs(c.du[3]), std::abs(c.du[4]));
                if (lin > max_linear) {
                    max_linear = lin;
                    max_linear_line = b.line;
                }
                if (rot > max_rotary) {
                    max_rotary = rot;
                    max_rotary_line = b.line;
                }
                if (c.singular) {
                    ++singular_count;
                    if (singular_lines.size() < 20) singular_lines.push_back(b.line);
                }
                b.X_mm = c.commanded.X_mm;
                b.Y_mm = c.commanded.Y_mm;
                b.Z_mm = c.commanded.Z_mm;
                b.A_rad = c.commanded.A_rad;
                if (second_is_c)
                    b.C_rad = c.commanded.C_rad;
                else
                    b.B_rad = c.commanded.B_rad;
                ++compensated;
            }
            ba::write_nc_block(chunk, b, dialect);
            if (chunk.size() >= kChunkBytes) flush();
        }
    } catch (const ba::NcError& e) {
        throw CliError(kExitUsage, args.program + ": " + e.what());  // `out` removes its .part
    }
    ba::write_nc_footer(chunk, dialect);
    flush();
    out.commit();
    std::ostream& report = out.is_stdout() ? std::cerr : std::cout;  // the program has stdout
    if (args.json) {
        json j{{"blocks", blocks},
               {"compensated", compensated},
               {"method", args.exact ? "exact" : "first-order"},
               {"max_linear_correction_mm", max_linear},
               {"max_linear_correction_line", max_linear_line},
               {"max_rotary_correction_deg", ba::rad_to_deg(max_rotary)},
               {"max_rotary_correction_line", max_rotary_line},
               {"singular_blocks", singular_count},
               {"singular_lines", singular_lines},
               {"out", args.out}};
        report << j.dump(2) << '\n';
    } else {
        report << "compensated " << compensated << " of " << blocks << " blocks ("
               << (args.exact ? "exact" : "first-order") << ") -> " << args.out << '\n'
               << "largest correction: " << max_linear * 1e3 << " um linear (line " << max_linear_line << "), "
               << ba::rad_to_deg(max_rotary) * 3600.0 << " arcsec rotary (line " << max_rotary_line << ")\n";
        if (singular_count > 0) {
            report << singular_count << " block(s) within " << args.singular_deg
                   << " deg of a singularity (rotary axis parallel to the tool): that axis was not corrected; lines";
            for (int l : singular_lines) report << ' ' << l;
            report << (singular_count > singular_lines.size() ? " ...\n" : "\n");
        }
    }
    return kExitOk;
}

}  // namespace
}  // namespace ballbar::app

BALLBAR_COMMAND(compensate) {
    using namespace ballbar::app;
    auto args = std::make_shared<CompensateArgs>();
    auto* sub = root.add_subcommand("compensate", "Rewrite an NC program through an identified error model");
    sub->add_option("--model", args->model, "ballbar-model/1 JSON file, model id or model name")->required();
    sub->add_option("--program", args->program, "NC program to compensate")->required();
    sub->add_option("--out", args->out, "where to write the compensated program ('-': standard output)")->required();
    sub->add_option("--dialect", args->dialect, "fanuc or linuxcnc (default: by extension, .ngc = linuxcnc)");
    sub->add_flag("--exact", args->exact, "exact (Newton) solution instead of the first-order Jacobian one");
    sub->add_option("--singular-deg", args->singular_deg,
                    "within this angle of a singularity the rotary axis is not corrected (default 0.06)")
        ->check(CLI::Range(0.0, 45.0));
    sub->add_flag("--json", args->json, "print the report as JSON");
    sub->footer("See docs/compensation.md.");
    sub->callback([&globals, args] { globals.action = [&globals, args]() { return run_compensate(*args, globals); }; });
}
