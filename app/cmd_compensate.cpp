// SPDX-License-Identifier: MIT
// `ballbar compensate --model MODEL --program IN.nc --out OUT.nc [--dialect D] [--exact] [--json]`:
// rewrites an NC program so that, on the machine described by the identified model, the tool ball
// lands where the program meant it relative to the table (compensate.hpp). MODEL is a
// `ballbar-model/1` JSON file (what `ballbar identify` stores), a model id in the database, or a model
// name (its latest version). Reports the largest correction and the blocks near a singularity.
#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/analysis/compensate.hpp"
#include "ballbar/analysis/limits.hpp"
#include "ballbar/analysis/nc_compensate.hpp"
#include "ballbar/workflow/compensate.hpp"
#include "command.hpp"
#include "files.hpp"

namespace ballbar::app {
namespace {

namespace ba = ballbar::analysis;
using nlohmann::json;

struct CompensateArgs {
    std::string model;
    std::string program;
    std::string out;
    std::string dialect;
    std::string offsets;
    std::string controller;
    std::string tcp_on, tcp_off;
    std::string start;  // "X0 Y0 Z100 A0 C0": where the machine is when the program starts
    bool tcp = false;
    bool iso_directions = false;
    double chord_tolerance_mm = 0.001;
    double max_correction_mm = 1.0;
    double max_correction_deg = 0.1;
    int decimals = 4;
    int max_iterations = 20;
    bool force = false;
    bool allow_truncated = false;
    bool exact = false;
    bool json = false;
    double singular_deg = ba::kDefaultSingularDeg;
};

/// Where the compensated program goes: fileio::OutputFile ("-" or /dev/stdout: standard output, and
/// the summary goes to stderr; a regular file is written beside it and renamed over it only by
/// commit(), so a program with an error leaves OUT as it was).
class OutputFile {
  public:
    OutputFile(const std::string& name, const std::vector<fileio::Protected>& inputs) try
        : file_(name, "--out", inputs) {
    } catch (const fileio::FileError& e) {
        throw as_error(e);
    }
    bool is_stdout() const { return file_.is_stdout(); }
    void write(std::string_view text) {
        try {
            file_.write(text);
        } catch (const fileio::FileError& e) {
            throw as_error(e);
        }
    }
    void commit() {
        try {
            if (file_.is_stdout()) std::cout.flush();
            file_.commit();
        } catch (const fileio::FileError& e) {
            throw as_error(e);
        }
    }

  private:
    fileio::OutputFile file_;
};

std::vector<std::string> split_codes(const std::string& list) {
    std::vector<std::string> out;
    std::string cur;
    for (char c : list + ",") {
        if (c == ',' || c == ' ') {
            if (!cur.empty()) out.push_back(cur);
            cur.clear();
        } else {
            cur += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
        }
    }
    return out;
}

/// --start "X0 Y0 Z100 A0 C0": every axis of the machine (mm, degrees), in the program's directions.
ba::Pose parse_start(const std::string& text, ba::MachineType type, bool iso_directions) {
    const char second = ba::rotary_axes(type).second;
    const std::string axes = std::string("XYZA") + second;
    ba::Pose p;
    unsigned named = 0;
    std::istringstream in(text);
    std::string word;
    auto bad = [&](const std::string& why) {
        return Error(ErrorCategory::bad_input, "--start \"" + text + "\": " + why + " (give every axis: X Y Z A " +
                                                   second + ", e.g. --start \"X0 Y0 Z100 A0 " + second + "0\")");
    };
    while (in >> word) {
        const char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(word[0])));
        const std::size_t k = axes.find(letter);
        if (k == std::string::npos) throw bad("'" + word + "' is not an axis of the model's machine");
        double v = 0;
        const char* first = word.data() + 1;
        const char* last = word.data() + word.size();
        const auto r = std::from_chars(first, last, v);
        if (word.size() < 2 || r.ec != std::errc() || r.ptr != last || !std::isfinite(v))
            throw bad("'" + word + "' is not an axis word with a number");
        if (named & (1u << k)) throw bad(std::string(1, letter) + " twice");
        named |= 1u << k;
        const double sign = iso_directions ? -1.0 : 1.0;
        switch (letter) {
            case 'X':
                p.X_mm = v;
                break;
            case 'Y':
                p.Y_mm = v;
                break;
            case 'Z':
                p.Z_mm = v;
                break;
            case 'A':
                p.A_rad = sign * ba::deg_to_rad(v);
                break;
            case 'B':
                p.B_rad = sign * ba::deg_to_rad(v);
                break;
            default:
                p.C_rad = sign * ba::deg_to_rad(v);
                break;
        }
    }
    if (named != 0b11111u) throw bad("an axis is missing");
    return p;
}

/// One warning per axis the program takes beyond the measured span (by more than 0.5° or 1 mm): "the
/// program commands A from -20° (line 5) to 90° (line 4); the model was measured from 0° to 15°: ...".
std::vector<std::string> beyond_measured(const ba::PoseRange& program, const ba::PoseRange& measured, bool linear_too) {
    std::vector<std::string> out;
    if (program.empty || measured.empty) return out;
    static constexpr const char* kNames[] = {"X", "Y", "Z", "A", "B", "C"};
    for (int i = 0; i < ba::PoseRange::kAxes; ++i) {
        const auto k = static_cast<std::size_t>(i);
        const bool rotary = i >= 3;
        if (!rotary && !linear_too) continue;
        const double scale = rotary ? ba::rad_to_deg(1.0) : 1.0, margin = rotary ? 0.5 : 1.0;
        const double lo = program.min[k] * scale, hi = program.max[k] * scale;
        const double mlo = measured.min[k] * scale, mhi = measured.max[k] * scale;
        const bool below = lo < mlo - margin;
        const bool above = hi > mhi + margin;
        if (!below && !above) continue;
        const char* unit = rotary ? "°" : " mm";
        auto v = [](double x) { return fmt::format("{:.4g}", x); };
        out.push_back(fmt::format(
            "the program commands {} from {}{} (line {}) to {}{} (line {}); the model was measured from {}{} to "
            "{}{}: its corrections beyond that are an extrapolation -- measure there too to be sure of them",
            kNames[k], v(lo), unit, program.min_line[k], v(hi), unit, program.max_line[k], v(mlo), unit, v(mhi), unit));
    }
    return out;
}

int run_compensate(const CompensateArgs& args, const Globals& globals) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (fs::is_directory(args.program, ec))
        throw Error(ErrorCategory::bad_input, "--program " + args.program + " is a directory, not an NC program");
    std::vector<fileio::Protected> inputs = database_files(globals);
    inputs.push_back({args.program, "program"});
    inputs.push_back({args.model, "model file"});  // when it names a file
    if (!args.offsets.empty()) inputs.push_back({args.offsets, "offsets table"});
    try {
        fileio::check_output(args.out, "--out", inputs);  // before any work
    } catch (const fileio::FileError& e) {
        throw as_error(e);
    }
    if (!(args.chord_tolerance_mm > 0)) throw Error(ErrorCategory::bad_input, "--chord-tolerance must be positive");

    const workflow::ModelChoice model =
        workflow::find_model(args.model, resolve_db_path(globals), globals.db_path.empty() ? "" : " (check --db)");
    // The corrections assume what the model could not determine: said before anything is written (in
    // the report's "warnings" with --json).
    std::vector<std::string> warnings;
    if (!model.model.unobservable.empty()) {
        std::string held;
        for (const auto p : model.model.unobservable)
            held += (held.empty() ? "" : ", ") + std::string(ba::param_info(p).name);
        warnings.push_back("the model holds " + held +
                           " at 0 (its readings could not determine them): the parameters that carry their effect "
                           "correct the tool-table relation at the poses it was measured at; `ballbar identify` "
                           "names them");
        if (!args.json) std::cerr << "ballbar: warning: " << warnings.back() << '\n';
    }
    workflow::ProgramCompensation pc;
    pc.dialect = args.dialect;
    pc.controller = args.controller;
    pc.tcp_on = split_codes(args.tcp_on);
    pc.tcp_off = split_codes(args.tcp_off);
    if (!args.offsets.empty()) {
        pc.offsets_json = read_file(args.offsets, "offsets table");
        pc.offsets_source = args.offsets;
    }
    pc.interpreter.tcp_at_start = args.tcp;
    if (!args.start.empty())
        pc.interpreter.start = parse_start(args.start, model.model.machine.type, args.iso_directions);
    pc.interpreter.iso_directions = args.iso_directions;
    pc.interpreter.chord_tolerance_mm = args.chord_tolerance_mm;
    pc.options.exact = args.exact;
    pc.options.solver.singular_tolerance = std::sin(ba::deg_to_rad(args.singular_deg));
    pc.options.max_linear_mm = args.max_correction_mm;
    pc.options.max_rotary_rad = ba::deg_to_rad(args.max_correction_deg);
    pc.options.force = args.force;
    pc.options.decimals = args.decimals;
    pc.options.solver.max_iterations = args.max_iterations;
    pc.options.allow_truncated = args.allow_truncated;
    workflow::program_dialect(pc, args.program);  // a wrong --dialect is said before the program is read
    const std::string text = read_program_file(args.program, "program");

    OutputFile out(args.out, inputs);
    // On an error `out` removes its .part: OUT stays as it was.
    const ba::NcCompensateSummary s =
        workflow::compensate_program(model, text, args.program, pc, [&](std::string_view chunk) { out.write(chunk); });
    // Where the program goes beyond the poses the model was measured at: there its corrections are the
    // model's extrapolation (a rotary axis's errors beyond the angles measured, a learned term beyond its
    // data). Rotary axes always; linear axes when the model holds learned terms (a rigid-body model's
    // location errors hold over the whole travel).
    if (model.model.measured_poses) {
        const std::vector<std::string> beyond =
            beyond_measured(s.commanded, *model.model.measured_poses, !model.model.empirical.empty());
        for (const std::string& b : beyond) {
            warnings.push_back(b);
            if (!args.json) std::cerr << "ballbar: warning: " << b << '\n';
        }
    }
    const bool failed = s.not_converged > 0 && !args.force;
    if (!failed) out.commit();
    std::ostream& report = out.is_stdout() ? std::cerr : std::cout;  // the program has stdout
    auto mode_name = [](ba::NcFrame f) { return f == ba::NcFrame::Tcp ? "tool-centre-point" : "joint"; };
    if (args.json) {
        // Line 0 is "no such block": null (docs/cli.md's vocabulary).
        const auto line_or_null = [](int line) { return line > 0 ? json(line) : json(nullptr); };
        json switches = json::array();
        for (const auto& [line, f] : s.mode_switches) switches.push_back({{"line", line}, {"mode", mode_name(f)}});
        json j{{"blocks", s.blocks},
               {"compensated", s.moves},
               {"points", s.points},
               {"arcs", s.arcs},
               {"arc_chords", s.arc_chords},
               {"chord_tolerance_mm", args.chord_tolerance_mm},
               {"modes", {{"joint", s.joint_moves}, {"tool_centre_point", s.tcp_moves}}},
               {"mode_switches", switches},
               {"retracts_uncompensated", s.retracts},
               {"method", args.exact ? "exact" : "first-order"},
               {"warnings", warnings},
               {"directions", args.iso_directions ? "iso" : "ballbar"},
               {"max_linear_correction_mm", s.max_linear_mm},
               {"max_linear_correction_line", line_or_null(s.max_linear_line)},
               {"max_rotary_correction_deg", ba::rad_to_deg(s.max_rotary_rad)},
               {"max_rotary_correction_line", line_or_null(s.max_rotary_line)},
               {"singular_blocks", s.singular},
               {"singular_lines", s.singular_lines},
               {"not_converged", s.not_converged},
               {"not_converged_lines", s.not_converged_lines},
               {"over_bound_forced", s.over_bound},
               {"truncated", s.truncated},
               {"written", !failed},
               {"out", args.out}};
        report << j.dump(2) << '\n';
    } else {
        report << "compensated " << s.moves << " of " << s.blocks << " blocks ("
               << (args.exact ? "exact" : "first-order") << ", " << s.points << " points) -> "
               << (failed ? "nothing written" : args.out) << '\n'
               << "modes: " << s.joint_moves << " joint, " << s.tcp_moves << " tool-centre-point";
        if (!s.mode_switches.empty()) {
            report << " (switches at lines";
            for (const auto& [line, f] : s.mode_switches) report << ' ' << line << ':' << mode_name(f);
            report << ')';
        }
        report << '\n';
        if (s.arcs > 0)
            report << s.arcs << " arc(s) as " << s.arc_chords << " chords within " << args.chord_tolerance_mm * 1e3
                   << " µm\n";
        if (s.retracts > 0) report << s.retracts << " retract(s) (G91 G28) copied uncompensated\n";
        report << "largest correction: " << s.max_linear_mm * 1e3 << " µm linear (line " << s.max_linear_line << "), "
               << ba::rad_to_deg(s.max_rotary_rad) * 3600.0 << " arcsec rotary (line " << s.max_rotary_line << ")\n";
        if (s.singular > 0) {
            report << s.singular << " point(s) within " << args.singular_deg
                   << " deg of a singularity (rotary axis parallel to the tool): that axis was not corrected; lines";
            for (int l : s.singular_lines) report << ' ' << l;
            report << (s.singular > s.singular_lines.size() ? " ...\n" : "\n");
        }
        if (s.over_bound > 0) report << s.over_bound << " correction(s) beyond the bound written (--force)\n";
        if (s.truncated) report << "the program has no end (M2/M30/%): compensated as it is (--allow-truncated)\n";
    }
    if (s.not_converged > 0) {
        std::string msg = "--exact did not converge for " + std::to_string(s.not_converged) + " point(s), lines";
        for (int l : s.not_converged_lines) msg += ' ' + std::to_string(l);
        throw Error(ErrorCategory::failed,
                    msg + (failed ? "; nothing written (--force writes it anyway)" : "; written (--force)"));
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
        ->check(in_range(0, 45, "°"));
    sub->add_option("--offsets", args->offsets, "work-offset and tool table (JSON, docs/compensation.md)");
    sub->add_option("--controller", args->controller,
                    "tool-centre-point codes of: linuxcnc (M428/M429), fanuc (G43.4/G49), siemens (TRAORI/TRAFOOF), "
                    "heidenhain (M128/M129), none (default: by dialect)");
    sub->add_option("--tcp-on", args->tcp_on, "words that switch tool-centre-point mode on (comma-separated)");
    sub->add_option("--tcp-off", args->tcp_off, "words that switch it off");
    sub->add_flag("--tcp", args->tcp, "the program starts in tool-centre-point (workpiece) coordinates");
    sub->add_option("--start", args->start,
                    "where the machine is when the program starts, in the frame of its first move: \"X Y Z A C\" "
                    "words (mm, degrees; e.g. \"X0 Y0 Z100 A0 C0\"); without it the first move must name every axis");
    sub->add_flag("--iso-directions", args->iso_directions,
                  "the program's +A/+C are ISO's (LinuxCNC conventional-directions): the opposite of ballbar's");
    sub->add_option("--chord-tolerance", args->chord_tolerance_mm,
                    "arcs are written as chords within this of the arc, mm (default 0.001)")
        ->check(in_range(1e-5, 0.1, "mm"));
    sub->add_option("--max-correction-mm", args->max_correction_mm, "refuse a larger linear correction (default 1)")
        ->check(in_range(1e-6, 100, "mm"));
    sub->add_option("--max-correction-deg", args->max_correction_deg,
                    "refuse a larger rotary correction; no angle moves more (default 0.1)")
        ->check(in_range(1e-6, 10, "°"));
    sub->add_option("--max-iterations", args->max_iterations, "--exact: Newton iterations at most (default 20)")
        ->check(in_range(1, 1000));
    sub->add_option("--decimals", args->decimals, "digits after the point of the axis words (default 4)")
        ->check(in_range(3, 8));
    sub->add_flag("--force", args->force, "write corrections beyond the bounds, and --exact non-convergence, anyway");
    sub->add_flag("--allow-truncated", args->allow_truncated, "compensate a program without M2/M30/% as it is");
    sub->add_flag("--json", args->json, "print the report as JSON");
    sub->footer("See docs/compensation.md.");
    sub->callback([&globals, args] { globals.action = [&globals, args]() { return run_compensate(*args, globals); }; });
}
