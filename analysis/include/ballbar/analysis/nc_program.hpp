// SPDX-License-Identifier: MIT
// NC programs of the subset ballbar writes and runs: G90 absolute, G0 rapid, G1 feed (F mm/min),
// G4 dwell, X Y Z A B C words (rotary in degrees in the text, radians here), comments.
// Two dialects: Fanuc-style (G4 P<ms>, "( comment )", "%" framing, O number) and LinuxCNC
// (G4 P<seconds>, "; comment" / "(comment)", M2 end). Parsing is pure text in, blocks out.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/analysis/types.hpp"

namespace ballbar::analysis {

enum class NcDialect { Fanuc, LinuxCNC };
std::string_view to_string(NcDialect d);
std::optional<NcDialect> parse_nc_dialect(std::string_view text);  // "fanuc", "linuxcnc"

enum class NcMotion { None, Rapid, Feed, Dwell };

/// One block. Axis words are optional: a block sets only the axes it names (modal absolute
/// positions are resolved by `resolve_poses`).
struct NcBlock {
    int line = 0;  ///< 1-based line in the source text (0 for generated blocks)
    NcMotion motion = NcMotion::None;
    std::optional<double> X_mm, Y_mm, Z_mm, A_rad, B_rad, C_rad;
    std::optional<double> feed_mm_min;
    double dwell_s = 0;       ///< G4 only
    std::string comment;      ///< text of a comment on the line, without delimiters
    std::string extra_words;  ///< machine-function words on the line (M8, S1000, T1), re-emitted on rewrite
    std::string raw;          ///< the source line of a block without motion (M3 S1000, T1 M6): kept on rewrite
};

struct NcProgram {
    NcDialect dialect = NcDialect::Fanuc;
    std::vector<NcBlock> blocks;
};

/// Error with the line number and the problem ("line 12: unknown G code G2 (ballbar runs G0, G1, G4, G90)").
class NcError : public AnalysisError {
  public:
    NcError(int line, const std::string& message);
    int line() const { return line_; }

  private:
    int line_;
};

/// Reads a program block by block without holding all of it (a million-block program streams through
/// `ballbar compensate` this way). `text` must outlive the reader.
class NcReader {
  public:
    NcReader(std::string_view text, NcDialect dialect);
    /// Fills `block` with the next block (every field is reset; its strings keep their capacity);
    /// false at the end of the text. Throws NcError.
    bool next(NcBlock& block);

  private:
    std::string_view text_;
    NcDialect dialect_;
    std::size_t pos_ = 0;
    int line_ = 0;
    NcMotion modal_ = NcMotion::None;  // G0/G1 stay in force for blocks with axis words only
};

/// Parses a program; the dialect decides how G4 P is read. Throws NcError.
NcProgram parse_nc_program(std::string_view text, NcDialect dialect);

/// Writes a program in its dialect; `parse_nc_program(write_nc_program(p), p.dialect)` gives p's
/// motion back (axis values to 1e-4 mm / 1e-4 degree).
std::string write_nc_program(const NcProgram& program, std::string_view title = {});

/// The writer in parts, for streaming: the framing and set-up lines, one block, the program end.
void write_nc_header(std::string& out, NcDialect dialect, std::string_view title = {});
void write_nc_block(std::string& out, const NcBlock& block, NcDialect dialect);
void write_nc_footer(std::string& out, NcDialect dialect);

/// Appends " <letter><value>" with `decimals` (0..8) digits after the point: exactly the text of
/// std::to_chars(value, std::chars_format::fixed, decimals) (the exact binary value rounded to
/// nearest, ties to even; "-" on negative values, zero included), at a fraction of its cost.
/// Every word is in the controller's word format or refused: finite; X Y Z A B C I J K R at most 5
/// integer digits (|value| < 100000); F positive and not rounded to zero, at most 6 (999999.9);
/// P not negative, at most 8. Throws AnalysisError (nc_word_problem's reason) otherwise.
void append_nc_number(std::string& out, char letter, double value, int decimals = 4);
/// Empty when append_nc_number(letter, value, decimals) would write the word; otherwise why not
/// ("NC word F: 1e-300 does not fit the controller's word format (> 0 to 999999.9, ...)").
std::string nc_word_problem(char letter, double value, int decimals);
/// The longest dwell a G4 takes, s (Fanuc: P in ms, at most 8 digits).
inline constexpr double kMaxDwell_s = 99'999.999;

/// The absolute commanded pose after `block` (the axes it does not name keep their `before` values).
Pose pose_after(const NcBlock& block, const Pose& before);

/// The absolute commanded pose after each block (modal axes carried forward from `start`).
std::vector<Pose> resolve_poses(const NcProgram& program, const Pose& start = {});

}  // namespace ballbar::analysis
