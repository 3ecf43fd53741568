// SPDX-License-Identifier: MIT
#include "document.hpp"

#include <cairo-pdf.h>

#include <algorithm>
#include <memory>
#include <numeric>
#include <string>

#include "ballbar/report/report.hpp"

namespace ballbar::report {

namespace {
constexpr double kTableSize = 7.0;
constexpr double kRowHeight = 11.5;
}  // namespace

Document::Document(cairo_surface_t* surface, std::string running_title, int total_pages, std::string kind)
    : cr_(cairo_create(surface)),
      running_title_(std::move(running_title)),
      kind_(std::move(kind)),
      total_pages_(total_pages) {}

Document::~Document() {
    cairo_destroy(cr_);
}

void Document::begin_page() {
    ++page_;
    open_ = true;
    y_ = kMargin;
    // Running header and footer.
    set_color(cr_, kGrey);
    set_font(cr_, 6.5);
    draw_text(cr_, kMargin, kMargin - 14, fit_text(cr_, running_title_, content_width() * 0.7), HAlign::Left,
              VAlign::Baseline);
    draw_text(cr_, kWidth - kMargin, kMargin - 14, kind_, HAlign::Right, VAlign::Baseline);
    cairo_set_line_width(cr_, 0.4);
    cairo_move_to(cr_, kMargin, kMargin - 10);
    cairo_line_to(cr_, kWidth - kMargin, kMargin - 10);
    cairo_stroke(cr_);
    const std::string footer = total_pages_ > 0
                                   ? "page " + std::to_string(page_) + " of " + std::to_string(total_pages_)
                                   : "page " + std::to_string(page_);
    draw_text(cr_, kWidth / 2, kHeight - kMargin + 6, footer, HAlign::Center, VAlign::Top);
    set_color(cr_, kBlack);
}

void Document::end_page() {
    if (!open_) return;
    cairo_show_page(cr_);
    open_ = false;
}

void Document::new_page() {
    end_page();
    begin_page();
}

void Document::ensure(double height) {
    if (!open_) begin_page();
    if (y_ + height > bottom_limit() && y_ > kMargin) new_page();
}

int Document::finish() {
    if (!open_ && page_ == 0) begin_page();
    end_page();
    return page_;
}

void Document::title(const std::string& text, const std::string& subtitle) {
    ensure(40);
    set_color(cr_, kBlack);
    set_font(cr_, 16, true);
    draw_text(cr_, kMargin, y_, fit_text(cr_, text, content_width()), HAlign::Left, VAlign::Top);
    y_ += 22;
    if (!subtitle.empty()) {
        set_font(cr_, 9);
        set_color(cr_, kGrey);
        draw_text(cr_, kMargin, y_, fit_text(cr_, subtitle, content_width()), HAlign::Left, VAlign::Top);
        y_ += 14;
    }
    set_color(cr_, kBlack);
    y_ += 4;
}

void Document::heading(const std::string& text, double keep_with_next) {
    ensure(22 + keep_with_next);
    y_ += 6;
    set_color(cr_, palette(0));
    set_font(cr_, 11, true);
    draw_text(cr_, kMargin, y_, fit_text(cr_, text, content_width()), HAlign::Left, VAlign::Top);
    y_ += 15;
    cairo_set_line_width(cr_, 0.5);
    cairo_move_to(cr_, kMargin, y_);
    cairo_line_to(cr_, kWidth - kMargin, y_);
    cairo_stroke(cr_);
    set_color(cr_, kBlack);
    y_ += 5;
}

void Document::paragraph(const std::string& text, double size, Rgb color) {
    set_font(cr_, size);
    for (const auto& line : wrap_text(cr_, text, content_width())) {
        ensure(size * 1.4);
        set_font(cr_, size);
        set_color(cr_, color);
        draw_text(cr_, kMargin, y_, line, HAlign::Left, VAlign::Top);
        y_ += size * 1.4;
    }
    set_color(cr_, kBlack);
    y_ += 3;
}

void Document::key_values(const std::vector<std::pair<std::string, std::string>>& rows, int columns) {
    columns = std::max(1, columns);
    const std::size_t per_col = (rows.size() + static_cast<std::size_t>(columns) - 1) / columns;
    const double col_w = content_width() / columns;
    const double line_h = 10.5;
    set_font(cr_, 7.5, true);
    double label_w = 0;
    for (const auto& [k, v] : rows) label_w = std::max(label_w, text_width(cr_, k));
    label_w = std::min(label_w + 8, col_w * 0.42);
    ensure(static_cast<double>(per_col) * line_h);
    for (std::size_t i = 0; i < rows.size(); ++i) {
        const auto c = static_cast<double>(i / per_col);
        const double x = kMargin + c * col_w, y = y_ + static_cast<double>(i % per_col) * line_h;
        set_font(cr_, 7.5, true);
        set_color(cr_, kGrey);
        draw_text(cr_, x, y, fit_text(cr_, rows[i].first, label_w - 4), HAlign::Left, VAlign::Top);
        set_font(cr_, 7.5);
        set_color(cr_, kBlack);
        draw_text(cr_, x + label_w, y, fit_text(cr_, rows[i].second, col_w - label_w - 8), HAlign::Left, VAlign::Top);
    }
    y_ += static_cast<double>(per_col) * line_h + 4;
}

void Document::table_row(const std::vector<Column>& columns, const std::vector<double>& widths,
                         const std::vector<std::string>& cells, bool header, bool shade) {
    if (shade || header) {
        set_color(cr_, header ? Rgb{0.88, 0.91, 0.95} : Rgb{0.96, 0.96, 0.96});
        cairo_rectangle(cr_, kMargin, y_, content_width(), kRowHeight);
        cairo_fill(cr_);
    }
    set_color(cr_, kBlack);
    set_font(cr_, kTableSize, header);
    double x = kMargin;
    for (std::size_t i = 0; i < columns.size(); ++i) {
        const std::string text = fit_text(cr_, i < cells.size() ? cells[i] : std::string(), widths[i] - 6);
        const HAlign a = header && columns[i].align == HAlign::Right ? HAlign::Right : columns[i].align;
        const double tx = a == HAlign::Left ? x + 3 : a == HAlign::Right ? x + widths[i] - 3 : x + widths[i] / 2;
        draw_text(cr_, tx, y_ + kRowHeight / 2, text, a, VAlign::Middle);
        x += widths[i];
    }
    y_ += kRowHeight;
}

void Document::table(const std::vector<Column>& columns, const std::vector<std::vector<std::string>>& rows) {
    const double total =
        std::accumulate(columns.begin(), columns.end(), 0.0, [](double s, const Column& c) { return s + c.weight; });
    std::vector<double> widths;
    for (const auto& c : columns) widths.push_back(content_width() * c.weight / total);
    std::vector<std::string> titles;
    for (const auto& c : columns) titles.push_back(c.title);

    ensure(kRowHeight * std::min<double>(3, 1 + static_cast<double>(rows.size())));
    table_row(columns, widths, titles, true, false);
    for (std::size_t r = 0; r < rows.size(); ++r) {
        if (y_ + kRowHeight > bottom_limit()) {  // continue on the next page under a repeated header
            new_page();
            table_row(columns, widths, titles, true, false);
        }
        table_row(columns, widths, rows[r], false, r % 2 == 1);
    }
    set_color(cr_, kGrey);
    cairo_set_line_width(cr_, 0.5);
    cairo_move_to(cr_, kMargin, y_);
    cairo_line_to(cr_, kWidth - kMargin, y_);
    cairo_stroke(cr_);
    set_color(cr_, kBlack);
    y_ += 6;
}

Rect Document::reserve(double height) {
    ensure(height);
    Rect r{kMargin, y_, content_width(), height};
    y_ += height + 8;
    return r;
}

void Document::verdict_line(const std::string& text, Rgb color) {
    const Rect area = reserve(16);
    set_color(cr(), color);
    set_font(cr(), 10.5, true);
    draw_text(cr(), area.x, area.y + 8, fit_text(cr(), text, area.w), HAlign::Left, VAlign::Middle);
    set_color(cr(), kBlack);
}

namespace {

using SurfacePtr = std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)>;

cairo_status_t discard_pdf(void*, const unsigned char*, unsigned int) {
    return CAIRO_STATUS_SUCCESS;
}

cairo_status_t append_pdf(void* closure, const unsigned char* data, unsigned int length) {
    static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
    return CAIRO_STATUS_SUCCESS;
}

}  // namespace

std::string two_pass_pdf(const std::function<int(cairo_surface_t*, int)>& layout, const std::string& title,
                         const std::string& creator, int* pages_out) {
    SurfacePtr counting(cairo_pdf_surface_create_for_stream(discard_pdf, nullptr, Document::kWidth, Document::kHeight),
                        cairo_surface_destroy);
    const int pages = layout(counting.get(), 0);
    cairo_surface_finish(counting.get());

    std::string pdf;
    SurfacePtr surface(cairo_pdf_surface_create_for_stream(append_pdf, &pdf, Document::kWidth, Document::kHeight),
                       cairo_surface_destroy);
    if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS)
        throw ReportError(std::string("cannot render the PDF: ") +
                          cairo_status_to_string(cairo_surface_status(surface.get())));
    cairo_pdf_surface_set_metadata(surface.get(), CAIRO_PDF_METADATA_TITLE, title.c_str());
    cairo_pdf_surface_set_metadata(surface.get(), CAIRO_PDF_METADATA_CREATOR, creator.c_str());
    const int written = layout(surface.get(), pages);
    cairo_surface_finish(surface.get());
    if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS)
        throw ReportError(std::string("cannot render the PDF: ") +
                          cairo_status_to_string(cairo_surface_status(surface.get())));
    if (pages_out) *pages_out = written;
    return pdf;
}

}  // namespace ballbar::report
