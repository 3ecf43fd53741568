// SPDX-License-Identifier: MIT
// Page layout on A4: margins, a running header and footer ("page i of n"), headings, wrapped text,
// key/value blocks and tables that break across pages (repeating their header row), and space reserved
// for figures. Content flows top to bottom; whatever does not fit starts a new page.
#pragma once

#include <cairo.h>

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "draw.hpp"

namespace ballbar::report {

struct Column {
    std::string title;
    double weight = 1;  ///< share of the table width
    HAlign align = HAlign::Left;
};

class Document {
  public:
    static constexpr double kWidth = 595.2756;   ///< A4, points
    static constexpr double kHeight = 841.8898;  ///< A4, points
    static constexpr double kMargin = 45;        ///< ≈ 16 mm

    /// Draws on `surface` (a PDF surface of A4 size). `total_pages` (0: unknown) goes into the footer.
    Document(cairo_surface_t* surface, std::string running_title, int total_pages,
             std::string kind = "ballbar session report");
    ~Document();
    Document(const Document&) = delete;
    Document& operator=(const Document&) = delete;

    cairo_t* cr() const { return cr_; }
    double content_width() const { return kWidth - 2 * kMargin; }
    double left() const { return kMargin; }
    /// Space left on the current page.
    double remaining() const { return bottom_limit() - y_; }

    void title(const std::string& text, const std::string& subtitle);
    /// A section heading; starts a new page if less than `keep_with_next` points would follow it.
    void heading(const std::string& text, double keep_with_next = 80);
    void paragraph(const std::string& text, double size = 7.5, Rgb color = kBlack);
    /// One line in bold, 10.5 pt, in `color` (a PASS/FAIL verdict).
    void verdict_line(const std::string& text, Rgb color);
    /// Two-column label/value lines, laid out in `columns` blocks side by side.
    void key_values(const std::vector<std::pair<std::string, std::string>>& rows, int columns = 2);
    void table(const std::vector<Column>& columns, const std::vector<std::vector<std::string>>& rows);
    /// A rectangle of the content width and `height` below the cursor (new page if it does not fit).
    Rect reserve(double height);
    void gap(double points) { y_ += points; }
    void new_page();
    /// Closes the last page; returns the number of pages.
    int finish();

  private:
    double bottom_limit() const { return kHeight - kMargin - 14; }
    void begin_page();
    void end_page();
    void ensure(double height);
    void table_row(const std::vector<Column>& columns, const std::vector<double>& widths,
                   const std::vector<std::string>& cells, bool header, bool shade);

    cairo_t* cr_;
    std::string running_title_;
    std::string kind_;  ///< the header's right-hand side: what document this is
    int total_pages_;
    int page_ = 0;
    bool open_ = false;
    double y_ = 0;
};

/// A PDF of A4 pages laid out twice by `layout(surface, total_pages)` (returning its pages): into nowhere
/// to count the pages, then into memory with the count in every footer. Throws ReportError when cairo fails.
std::string two_pass_pdf(const std::function<int(cairo_surface_t*, int)>& layout, const std::string& title,
                         const std::string& creator, int* pages = nullptr);

}  // namespace ballbar::report
