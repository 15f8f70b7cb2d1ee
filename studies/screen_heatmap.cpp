#include "studies/screen_heatmap.hpp"

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace gapflow {

namespace {

constexpr double kCell = 72, kMarginLeft = 70, kMarginTop = 56, kGapBetween = 80, kMarginBottom = 70;

struct Rgb {
  double r, g, b;
};

// Diverging scale: 0.5 -> blue, 1 -> white, 1.5 -> red (clamped).
Rgb ratio_colour(double v) {
  const double t = std::clamp((v - 1.0) / 0.5, -1.0, 1.0);
  if (t < 0) return {1 + 0.75 * t, 1 + 0.45 * t, 1.0};
  return {1.0, 1 - 0.75 * t, 1 - 0.8 * t};
}

// Sequential scale for the clog rate: 0 -> white, >= 10 per 100 -> orange.
Rgb clog_colour(double v) {
  const double t = std::clamp(v / 10.0, 0.0, 1.0);
  return {1.0, 1 - 0.45 * t, 1 - 0.9 * t};
}

void text_at(cairo_t* cr, const std::string& s, double cx, double cy, double size, bool bold = false) {
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
  cairo_text_extents_t e;
  cairo_text_extents(cr, s.c_str(), &e);
  cairo_move_to(cr, cx - e.width / 2 - e.x_bearing, cy - e.height / 2 - e.y_bearing);
  cairo_show_text(cr, s.c_str());
}

void panel(cairo_t* cr, const HeatMap& m, double x0, bool side) {
  const double rows = static_cast<double>(m.ys.size());
  cairo_set_source_rgb(cr, 0, 0, 0);
  text_at(cr, side ? m.right_title : m.left_title, x0 + kCell * m.xs.size() / 2, kMarginTop - 14, 14, true);
  for (const HeatCell& c : m.cells) {
    const double x = x0 + kCell * c.ix, y = kMarginTop + kCell * (rows - 1 - c.iy);
    Rgb fill{0.85, 0.85, 0.85};
    if (c.state == HeatCell::State::final) fill = side ? clog_colour(c.side_value) : ratio_colour(c.value);
    if (c.state == HeatCell::State::dropped && side && c.side_value >= 0) fill = clog_colour(c.side_value);
    if (c.state == HeatCell::State::infeasible || c.state == HeatCell::State::missing) fill = {0.6, 0.6, 0.6};
    cairo_set_source_rgb(cr, fill.r, fill.g, fill.b);
    cairo_rectangle(cr, x, y, kCell, kCell);
    cairo_fill(cr);
    if (c.state == HeatCell::State::dropped && !side) {  // hatched: no final estimate
      cairo_set_source_rgb(cr, 0.6, 0.6, 0.6);
      cairo_set_line_width(cr, 1);
      for (double k = 8; k < 2 * kCell; k += 12) {
        cairo_move_to(cr, x + std::max(0.0, k - kCell), y + std::min(k, kCell));
        cairo_line_to(cr, x + std::min(k, kCell), y + std::max(0.0, k - kCell));
      }
      cairo_stroke(cr);
    }
    if (c.state == HeatCell::State::infeasible) {
      cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
      cairo_move_to(cr, x + 8, y + 8);
      cairo_line_to(cr, x + kCell - 8, y + kCell - 8);
      cairo_move_to(cr, x + kCell - 8, y + 8);
      cairo_line_to(cr, x + 8, y + kCell - 8);
      cairo_stroke(cr);
    }
    cairo_set_source_rgb(cr, 0, 0, 0);
    text_at(cr, side ? c.side_text : c.text, x + kCell / 2, y + kCell / 2, 11,
            c.state == HeatCell::State::final && !side && c.text.find('*') != std::string::npos);
  }
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_set_line_width(cr, 1);
  cairo_rectangle(cr, x0, kMarginTop, kCell * m.xs.size(), kCell * rows);
  cairo_stroke(cr);
  for (std::size_t i = 0; i < m.xs.size(); ++i)
    text_at(cr, m.xs[i], x0 + kCell * (i + 0.5), kMarginTop + kCell * rows + 12, 11);
  text_at(cr, m.xlabel, x0 + kCell * m.xs.size() / 2, kMarginTop + kCell * rows + 30, 12);
  for (std::size_t j = 0; j < m.ys.size(); ++j)
    text_at(cr, m.ys[j], x0 - 18, kMarginTop + kCell * (rows - 1 - j + 0.5), 11);
}

}  // namespace

void draw_heatmap_png(const HeatMap& m, const std::filesystem::path& file) {
  const double panel_w = kCell * static_cast<double>(std::max<std::size_t>(1, m.xs.size()));
  const int width = std::max(640, static_cast<int>(kMarginLeft + 2 * panel_w + kGapBetween + 20));
  const int height = static_cast<int>(kMarginTop + kCell * static_cast<double>(m.ys.size()) + kMarginBottom + 14);
  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_ARGB32, width, height);
  cairo_t* cr = cairo_create(surface);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_set_source_rgb(cr, 0, 0, 0);
  text_at(cr, m.title, width / 2.0, 16, 14, true);
  panel(cr, m, kMarginLeft, false);
  panel(cr, m, kMarginLeft + panel_w + kGapBetween, true);
  cairo_save(cr);  // the y label, rotated
  cairo_translate(cr, 16, kMarginTop + kCell * m.ys.size() / 2);
  cairo_rotate(cr, -M_PI / 2);
  text_at(cr, m.ylabel, 0, 0, 12);
  cairo_restore(cr);
  const std::size_t split = m.legend.find("; ");  // two lines: the legend is wider than a small map
  text_at(cr, m.legend.substr(0, split), width / 2.0, height - 26, 10);
  if (split != std::string::npos) text_at(cr, m.legend.substr(split + 2), width / 2.0, height - 12, 10);
  cairo_destroy(cr);
  const cairo_status_t status = cairo_surface_write_to_png(surface, file.c_str());
  cairo_surface_destroy(surface);
  if (status != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error("cannot write " + file.string() + ": " + cairo_status_to_string(status));
}

}  // namespace gapflow
