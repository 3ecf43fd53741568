// SPDX-License-Identifier: MIT
// Small drawing helpers over cairo's toy text API (DejaVu Sans): fonts, aligned text, wrapping, colours.
#pragma once

#include <cairo.h>

#include <string>
#include <string_view>
#include <vector>

namespace ballbar::report {

struct Rgb {
    double r = 0, g = 0, b = 0;
};

struct Rect {
    double x = 0, y = 0, w = 0, h = 0;
    double right() const { return x + w; }
    double bottom() const { return y + h; }
};

/// Distinguishable colours (Okabe–Ito, readable by colour-blind readers and in greyscale print).
Rgb palette(int i);
inline constexpr Rgb kBlack{0, 0, 0};
inline constexpr Rgb kGrey{0.45, 0.45, 0.45};
inline constexpr Rgb kLightGrey{0.85, 0.85, 0.85};
inline constexpr Rgb kPass{0.0, 0.55, 0.25};  ///< a verdict within tolerance
inline constexpr Rgb kFail{0.80, 0.10, 0.10};

enum class HAlign { Left, Center, Right };
enum class VAlign { Baseline, Top, Middle, Bottom };

void set_color(cairo_t* cr, Rgb c, double alpha = 1.0);
void set_font(cairo_t* cr, double size_pt, bool bold = false);
double text_width(cairo_t* cr, std::string_view text);
/// Draws `text` with its anchor at (x, y).
void draw_text(cairo_t* cr, double x, double y, std::string_view text, HAlign h = HAlign::Left,
               VAlign v = VAlign::Baseline);
/// Draws `text` rotated 90° counter-clockwise (reading bottom to top), centred on (x, y).
void draw_text_vertical(cairo_t* cr, double x, double y, std::string_view text);
/// `text` cut at a character boundary and ended with "…" so it fits in `width`.
std::string fit_text(cairo_t* cr, std::string_view text, double width);
/// Splits `text` at spaces into lines no wider than `width` (a longer word is cut with fit_text).
std::vector<std::string> wrap_text(cairo_t* cr, std::string_view text, double width);

}  // namespace ballbar::report
