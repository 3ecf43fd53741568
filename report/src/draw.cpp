// SPDX-License-Identifier: MIT
#include "draw.hpp"

#include <array>
#include <string>

namespace ballbar::report {

Rgb palette(int i) {
    static constexpr std::array<Rgb, 7> kColors{{{0.000, 0.447, 0.698},
                                                 {0.835, 0.369, 0.000},
                                                 {0.000, 0.620, 0.451},
                                                 {0.800, 0.475, 0.655},
                                                 {0.902, 0.624, 0.000},
                                                 {0.337, 0.706, 0.914},
                                                 {0.941, 0.894, 0.259}}};
    return kColors[static_cast<std::size_t>(i < 0 ? -i : i) % kColors.size()];
}

void set_color(cairo_t* cr, Rgb c, double alpha) {
    cairo_set_source_rgba(cr, c.r, c.g, c.b, alpha);
}

void set_font(cairo_t* cr, double size_pt, bool bold) {
    cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL,
                           bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, size_pt);
}

double text_width(cairo_t* cr, std::string_view text) {
    const std::string s(text);
    cairo_text_extents_t te;
    cairo_text_extents(cr, s.c_str(), &te);
    return te.x_advance;
}

void draw_text(cairo_t* cr, double x, double y, std::string_view text, HAlign h, VAlign v) {
    const std::string s(text);
    cairo_font_extents_t fe;
    cairo_font_extents(cr, &fe);
    double dx = 0;
    if (h != HAlign::Left) {
        const double w = text_width(cr, s);
        dx = h == HAlign::Center ? -w / 2 : -w;
    }
    double dy = 0;
    switch (v) {
        case VAlign::Baseline:
            break;
        case VAlign::Top:
            dy = fe.ascent;
            break;
        case VAlign::Middle:
            dy = (fe.ascent - fe.descent) / 2;
            break;
        case VAlign::Bottom:
            dy = -fe.descent;
            break;
    }
    cairo_move_to(cr, x + dx, y + dy);
    cairo_show_text(cr, s.c_str());
}

void draw_text_vertical(cairo_t* cr, double x, double y, std::string_view text) {
    cairo_save(cr);
    cairo_translate(cr, x, y);
    cairo_rotate(cr, -1.5707963267948966);
    draw_text(cr, 0, 0, text, HAlign::Center, VAlign::Middle);
    cairo_restore(cr);
}

namespace {
// Length of the longest prefix of `s` that ends on a UTF-8 character boundary and is at most `n` bytes.
std::size_t utf8_prefix(std::string_view s, std::size_t n) {
    if (n >= s.size()) return s.size();
    while (n > 0 && (static_cast<unsigned char>(s[n]) & 0xC0u) == 0x80u) --n;
    return n;
}
}  // namespace

std::string fit_text(cairo_t* cr, std::string_view text, double width) {
    if (text_width(cr, text) <= width) return std::string(text);
    std::size_t n = text.size();
    while (n > 0) {
        n = utf8_prefix(text, n - 1);
        if (text_width(cr, std::string(text.substr(0, n)) + "…") <= width) break;
    }
    return std::string(text.substr(0, n)) + "…";
}

std::vector<std::string> wrap_text(cairo_t* cr, std::string_view text, double width) {
    std::vector<std::string> lines;
    std::string line;
    std::size_t i = 0;
    while (i <= text.size()) {
        const std::size_t j = std::min(text.find(' ', i), text.size());
        const std::string word(text.substr(i, j - i));
        const std::string candidate = line.empty() ? word : line + " " + word;
        if (line.empty() || text_width(cr, candidate) <= width) {
            line = candidate;
        } else {
            lines.push_back(fit_text(cr, line, width));
            line = word;
        }
        i = j + 1;
    }
    if (!line.empty() || lines.empty()) lines.push_back(fit_text(cr, line, width));
    return lines;
}

}  // namespace ballbar::report
