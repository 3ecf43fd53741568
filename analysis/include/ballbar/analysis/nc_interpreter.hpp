// SPDX-License-Identifier: MIT
// The CAM-program interpreter of `ballbar compensate` (docs/compensation.md, "Real programs"): a modal
// state machine over the blocks of a part program, giving for each block its motion as segments with
// resolved absolute end points. NcReader (nc_program.hpp) stays the reader of the programs ballbar
// writes for its own procedures; this is the layer for what a CAM system writes.
//
// Understood: modal axis words and motion (G0 G1 G2 G3), G90/G91, G90.1/G91.1, G20/G21, G17/G18/G19,
// G93/G94, G54–G59 (and G59.1–G59.3), G53, G43 H / G43.4 H / G49, T and M6, N, ( ) and ; comments,
// G4, G40, G80, G61/G64, "G91 G28 Z0", tool-centre-point mode switches (configurable words), and any
// M code (passed through). Refused with the reason: parameters (#), expressions ([ ]), O-word
// subroutines and macro calls, cutter radius compensation, canned cycles, other G codes, axes the
// model does not have, duplicate words.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/analysis/nc_program.hpp"
#include "ballbar/analysis/types.hpp"

namespace ballbar::analysis {

/// The work-offset and tool table the user gives (docs/compensation.md, "The offsets table").
/// Values are in the controller's direction convention; lengths mm, angles rad.
struct NcOffsetTable {
    std::map<std::string, Pose> work;      ///< "G54" … "G59", "G59.1" … : the work origin
    std::map<int, double> tool_length_mm;  ///< H / tool number → length
    double measured_tool_length_mm = 0;    ///< the tool length in force while the model was measured
};

/// The words that switch a controller's tool-centre-point mode on and off ("M428", "G43.4", "TRAORI").
struct TcpCodes {
    std::vector<std::string> on, off;
};
/// Presets: "linuxcnc" (M428 on, M429 off), "fanuc" (G43.4 on, G49 off), "siemens" (TRAORI, TRAFOOF),
/// "heidenhain" (M128, M129), "none".
std::optional<TcpCodes> tcp_codes_for(std::string_view controller);

struct NcInterpreterOptions {
    NcDialect dialect = NcDialect::Fanuc;
    char second_rotary = 'C';  ///< the model's rotary axes are A and this; other rotary words are refused
    NcOffsetTable offsets;
    bool have_offsets = false;  ///< G54–G59 and G43 need a table (else refused)
    TcpCodes tcp;
    bool tcp_at_start = false;          ///< the program starts in tool-centre-point mode
    bool iso_directions = false;        ///< program +A/+C are ISO's: negated to ballbar's (and back on output)
    double chord_tolerance_mm = 0.001;  ///< arcs are split into chords within this of the arc
    /// Where the machine is when the program starts, in the program coordinates of the frame its first
    /// move is in (ballbar directions; a switch of frame before any move keeps it). Without it the
    /// first move must name every axis.
    std::optional<Pose> start;
};

enum class NcFrame { Joint, Tcp };

/// One block, interpreted.
struct NcStep {
    int line = 0;
    NcMotion motion = NcMotion::None;  ///< Rapid or Feed (G1, G2, G3) when the block moves
    bool arc = false;
    bool machine_coordinates = false;  ///< G53: points are machine positions, no offsets
    NcFrame frame = NcFrame::Joint;
    int frame_line = 0;               ///< the line of the switch that put `frame` in force (0: from the start)
    bool inverse_time = false;        ///< G93 in force: F is 1/min for the whole block
    std::optional<double> feed;       ///< F in the block (mm/min, or 1/min under G93)
    std::vector<Pose> points;         ///< absolute end points of the segments (program frame, ballbar directions)
    Pose start;                       ///< absolute position before the block (program frame)
    Pose work_offset;                 ///< in force (ballbar directions), zero under G53
    bool tool_length_active = false;  ///< G43/G43.4 in force
    double tool_length_mm = 0;
    std::string sequence;  ///< "N10" or empty
    std::string words;     ///< other words re-emitted as written (M8, S1000, T2 M6, G54, G43 H1, M428)
    std::string comment;
    std::string verbatim;      ///< a line copied as it is (a "G91 G28 Z0" retract)
    bool program_end = false;  ///< M2, M30 or a closing %
};

/// Interprets a program block by block without holding all of it. `text` must outlive it. Throws
/// NcError naming the line and the reason.
class NcInterpreter {
  public:
    NcInterpreter(std::string_view text, NcInterpreterOptions options);
    /// The next block with something to write; false after the program end or the end of the text.
    bool next(NcStep& step);
    /// An M2, M30 or closing % was seen.
    bool ended() const { return ended_; }
    /// Blocks that were read (lines with words).
    std::size_t blocks() const { return blocks_; }
    /// The last line read.
    int line() const { return line_; }

  private:
    void parse_line(std::string_view raw, NcStep& step);
    void arc_points(NcStep& step, const Pose& end, double i, double j, double k, std::optional<double> r, bool cw,
                    bool have_ijk);

    bool is_tcp_code(char letter, double value) const;

    std::string_view text_;
    NcInterpreterOptions opt_;
    std::vector<std::pair<char, double>> tcp_numeric_;  // the G/M switch codes as (letter, number)
    std::size_t pos_ = 0;
    int line_ = 0;
    std::size_t blocks_ = 0;
    bool ended_ = false;
    bool started_ = false;  // a block or a leading % was seen
    // modal state
    int motion_ = -1;  // 0, 1, 2, 3 (G code), -1 none
    bool absolute_ = true, arc_absolute_ = false, inch_ = false, inverse_time_ = false;
    int plane_ = 17;
    bool tcp_ = false;
    int frame_line_ = 0;  // the line of the last frame switch
    bool moved_ = false;  // a move was read
    bool tool_length_active_ = false;
    double tool_length_mm_ = 0;
    int tool_ = 0, next_tool_ = 0;
    Pose work_offset_;
    Pose pos_now_;   // absolute program-frame position
    int known_ = 0;  // bit k: axis k (X Y Z A B C) has a known position in the current frame
};

}  // namespace ballbar::analysis
