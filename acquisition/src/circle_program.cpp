// SPDX-License-Identifier: MIT
#include "ballbar/acquisition/circle_program.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "ballbar/acquisition/machine_file.hpp"
#include "ballbar/analysis/limits.hpp"
#include "ballbar/analysis/nc_program.hpp"

namespace ballbar::acquisition {

namespace circ = analysis::circular;

std::string nc_number(double v) {
    std::ostringstream os;
    os << std::fixed << std::setprecision(4) << v;
    std::string s = os.str();
    while (!s.empty() && s.back() == '0') s.pop_back();
    if (!s.empty() && s.back() == '.') s.pop_back();
    return s == "-0" ? "0" : s;
}

std::string circular_program(const circ::TestSpec& t, analysis::NcDialect dialect, double dwell_s) {
    constexpr double kPi = 3.14159265358979323846;
    const auto ax = circ::plane_axis_index(t.plane);
    const char* letters = "XYZ";
    const char* centre_words = "IJK";
    const char* gplane = t.plane == circ::Plane::XY ? "G17" : t.plane == circ::Plane::ZX ? "G18" : "G19";
    const double cp = t.centre_mm[static_cast<std::size_t>(ax[0])], cq = t.centre_mm[static_cast<std::size_t>(ax[1])];
    auto point = [&](double r, double deg) {
        std::array<double, 3> p = t.centre_mm;
        p[static_cast<std::size_t>(ax[0])] = cp + r * std::cos(deg * kPi / 180.0);
        p[static_cast<std::size_t>(ax[1])] = cq + r * std::sin(deg * kPi / 180.0);
        return p;
    };
    const auto& num = nc_number;
    const bool fanuc = dialect == analysis::NcDialect::Fanuc;
    // Every number written is in the controller's word format (4 decimals at most), or nothing is written.
    auto word = [&](char letter, double v) {
        if (const std::string why = analysis::nc_word_problem(letter, v, 4); !why.empty())
            throw PlanError("the circle's program: " + why);
        return std::string(" ") + letter + num(v);
    };
    if (!(dwell_s >= 0 && dwell_s <= 3600))
        throw PlanError("--dwell " + analysis::limits::check_in(dwell_s, 0, 3600, "s"));
    std::string out;
    analysis::write_nc_header(out, dialect, std::string("ballbar circular test ") + circ::plane_name(t.plane));
    auto comment = [&](const std::string& text) { out += "(" + text + ")\n"; };
    auto move = [&](const char* g, const std::array<double, 3>& p, bool with_feed) {
        out += g;
        for (int i = 0; i < 3; ++i) out += word(letters[i], p[static_cast<std::size_t>(i)]);
        if (with_feed) out += word('F', t.feed_mm_min);
        out += '\n';
    };
    auto dwell = [&] {
        out += fanuc ? "G4 P" + std::to_string(std::lround(dwell_s * 1000.0)) + "\n" : "G4 P" + num(dwell_s) + "\n";
    };
    out += gplane;
    out += '\n';
    comment("plane " + std::string(circ::plane_name(t.plane)) + ", radius " + num(t.radius_mm) + " mm, feed " +
            num(t.feed_mm_min) + " mm/min, feed-in " + num(t.feed_in_mm) + " mm");
    for (std::size_t k = 0; k < t.runs.size(); ++k) {
        const circ::RunSpec& r = t.runs[k];
        const double sg = r.direction == circ::Direction::Ccw ? 1.0 : -1.0;
        comment("run " + std::to_string(k + 1) + ": " + circ::direction_name(r.direction) + " from " +
                num(r.start_deg) + " deg, overshoot " + num(r.overshoot_deg) + " deg, data arc " + num(r.data_arc_deg) +
                " deg");
        if (k == 0) move("G0", point(t.radius_mm + t.feed_in_mm, r.start_deg), false);
        dwell();
        move("G1", point(t.radius_mm, r.start_deg), true);  // feed-in
        const double sweep = 2.0 * r.overshoot_deg + r.data_arc_deg;
        const int pieces = std::max(1, static_cast<int>(std::ceil(sweep / 90.0 - 1e-9)));
        double a = r.start_deg;
        for (int i = 0; i < pieces; ++i) {
            const double b = r.start_deg + sg * sweep * (i + 1) / pieces;
            const auto from = point(t.radius_mm, a), to = point(t.radius_mm, b);
            out += sg > 0 ? "G3" : "G2";
            for (int j : {ax[0], ax[1]}) out += word(letters[j], to[static_cast<std::size_t>(j)]);
            for (int j : {ax[0], ax[1]})
                out +=
                    word(centre_words[j], t.centre_mm[static_cast<std::size_t>(j)] - from[static_cast<std::size_t>(j)]);
            out += word('F', t.feed_mm_min) + '\n';
            a = b;
        }
        move("G1", point(t.radius_mm + t.feed_in_mm, a), true);  // feed-out
    }
    dwell();
    analysis::write_nc_footer(out, dialect);
    return out;
}

}  // namespace ballbar::acquisition
