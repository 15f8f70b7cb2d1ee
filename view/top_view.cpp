#include "view/top_view.hpp"

#include "common/clog_front.hpp"

#include <algorithm>
#include <array>
#include <cairo.h>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <stdexcept>

namespace gapflow {

namespace {

constexpr int kCaptionPx = 44;   // caption band above the board
constexpr int kLegendPx = 84;    // colour bar / state legend band right of the board
constexpr int kMarginPx = 6;

// matplotlib's viridis at 0, 1/8, ..., 1 (perceptually uniform, colour-blind safe).
constexpr std::array<std::array<double, 3>, 9> kViridis{{{0.267004, 0.004874, 0.329415},
                                                         {0.282623, 0.140926, 0.457517},
                                                         {0.229739, 0.322361, 0.545706},
                                                         {0.172719, 0.448791, 0.557885},
                                                         {0.127568, 0.566949, 0.550556},
                                                         {0.157851, 0.683765, 0.501686},
                                                         {0.369214, 0.788888, 0.382914},
                                                         {0.678489, 0.863742, 0.189503},
                                                         {0.993248, 0.906157, 0.143936}}};

unsigned char byte_of(double c) { return static_cast<unsigned char>(std::lround(std::clamp(c, 0.0, 1.0) * 255)); }
void set_source(cairo_t* cr, Rgb c) { cairo_set_source_rgb(cr, c.r / 255.0, c.g / 255.0, c.b / 255.0); }

}  // namespace

Colouring parse_colouring(const std::string& name) {
  if (name == "speed") return Colouring::speed;
  if (name == "state") return Colouring::state;
  throw std::invalid_argument("colouring '" + name + "' is not one of: speed, state");
}

Rgb speed_colour(double speed, double speed_max) {
  const double u = std::clamp(speed_max > 0 ? speed / speed_max : 0.0, 0.0, 1.0) * 8;
  const int i = std::min(7, static_cast<int>(u));
  const double f = u - i;
  const auto& a = kViridis[static_cast<size_t>(i)];
  const auto& b = kViridis[static_cast<size_t>(i + 1)];
  return {byte_of(a[0] + f * (b[0] - a[0])), byte_of(a[1] + f * (b[1] - a[1])), byte_of(a[2] + f * (b[2] - a[2]))};
}

Rgb state_colour(ParticleState s) {
  switch (s) {
    case ParticleState::flowing: return {49, 114, 204};
    case ParticleState::arch: return {220, 38, 28};
    case ParticleState::passed: return {150, 150, 150};
    case ParticleState::stuck: return {240, 160, 40};
  }
  return {};
}
Rgb wall_colour() { return {60, 62, 70}; }
Rgb obstruction_colour() { return {140, 90, 50}; }
Rgb board_colour() { return {246, 243, 232}; }

TopView::TopView(const CompiledScenario& sc, TopViewDef def) : sc_(sc), def_(std::move(def)) {
  if (!(def_.px_per_mm > 0) || def_.px_per_mm > 20)
    throw std::invalid_argument(fmt::format("px_per_mm = {} is not in (0, 20]", def_.px_per_mm));
  scale_ = def_.px_per_mm * 1e3;
  const double side = sc.wall_thickness + 0.005;  // m shown outside the retaining walls
  x_min_ = -sc.channel_width / 2 - side;
  y_max_ = sc.plane_length + side;
  const double y_min = -def_.below_gap_mm * 1e-3;
  board_w_ = static_cast<int>(std::ceil((sc.channel_width + 2 * side) * scale_));
  board_h_ = static_cast<int>(std::ceil((y_max_ - y_min) * scale_));
  board_left_ = kMarginPx;
  board_top_ = kCaptionPx;
  width_ = (board_left_ + board_w_ + kLegendPx + 1) / 2 * 2;
  height_ = (board_top_ + board_h_ + kMarginPx + 1) / 2 * 2;
  surface_ = cairo_image_surface_create(CAIRO_FORMAT_ARGB32, width_, height_);
  if (cairo_surface_status(surface_) != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error(fmt::format("cairo: cannot create a {} x {} picture", width_, height_));
}

TopView::~TopView() { cairo_surface_destroy(surface_); }

TopView::Pixel TopView::to_pixel(Vec2 m) const {
  return {board_left_ + static_cast<int>(std::floor((m.x - x_min_) * scale_)),
          board_top_ + static_cast<int>(std::floor((y_max_ - m.y) * scale_))};
}

Rgb TopView::colour_at(Pixel p) const {
  cairo_surface_flush(surface_);
  const unsigned char* px = data() + static_cast<size_t>(p.row) * static_cast<size_t>(stride()) + 4 * p.col;
  return {px[2], px[1], px[0]};  // BGRA in memory
}

const unsigned char* TopView::data() const { return cairo_image_surface_get_data(surface_); }
int TopView::stride() const { return cairo_image_surface_get_stride(surface_); }

void TopView::draw(const FrameState& f) {
  cairo_t* cr = cairo_create(surface_);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_save(cr);
  cairo_rectangle(cr, board_left_, board_top_, board_w_, board_h_);
  cairo_clip(cr);
  // Board coordinates: metres, y up.
  cairo_translate(cr, board_left_ - x_min_ * scale_, board_top_ + y_max_ * scale_);
  cairo_scale(cr, scale_, -scale_);
  draw_board(cr, f);
  draw_particles(cr, f);
  cairo_restore(cr);
  draw_caption(cr, f);
  draw_legend(cr);
  cairo_destroy(cr);
  cairo_surface_flush(surface_);
}

namespace {

void polygon_path(cairo_t* cr, const ConvexPolygon& p, Vec2 offset) {
  for (size_t i = 0; i < p.vertices.size(); ++i) {
    const Vec2 v = p.vertices[i];
    (i == 0 ? cairo_move_to : cairo_line_to)(cr, v.x + offset.x, v.y + offset.y);
  }
  cairo_close_path(cr);
}

}  // namespace

void TopView::draw_board(cairo_t* cr, const FrameState& f) const {
  set_source(cr, board_colour());
  cairo_paint(cr);
  set_source(cr, wall_colour());
  polygon_path(cr, sc_.left_bottleneck_wall, f.offsets.left_wall);
  polygon_path(cr, sc_.right_bottleneck_wall, f.offsets.right_wall);
  polygon_path(cr, sc_.left_retaining_wall, {});
  polygon_path(cr, sc_.right_retaining_wall, {});
  polygon_path(cr, sc_.top_wall, {});
  cairo_fill(cr);

  const ObstructionGeometry ob = displaced(sc_.obstruction, f.offsets.obstruction);
  if (ob.shape == ObstructionShape::cylinder) {
    cairo_arc(cr, ob.circle.centre.x, ob.circle.centre.y, ob.circle.radius, 0, 2 * M_PI);
  } else if (ob.shape != ObstructionShape::none) {
    polygon_path(cr, ob.polygon, {});
  }
  set_source(cr, obstruction_colour());
  cairo_fill(cr);

  // The gap line between the (shaken) wall tips.
  const Vec2 a{sc_.left_tip.x + f.offsets.left_wall.x, sc_.left_tip.y + f.offsets.left_wall.y};
  const Vec2 b{sc_.right_tip.x + f.offsets.right_wall.x, sc_.right_tip.y + f.offsets.right_wall.y};
  cairo_move_to(cr, a.x, a.y);
  cairo_line_to(cr, b.x, b.y);
  cairo_set_source_rgb(cr, 0.85, 0.1, 0.55);
  cairo_set_line_width(cr, 1.5 / scale_);
  const double dash[] = {4 / scale_, 3 / scale_};
  cairo_set_dash(cr, dash, 2, 0);
  cairo_stroke(cr);
  cairo_set_dash(cr, nullptr, 0, 0);
}

void TopView::draw_particles(cairo_t* cr, const FrameState& f) const {
  const double outline = std::min(0.6 / scale_, 0.1 * sc_.nominal_diameter);
  cairo_set_line_width(cr, outline);
  for (const ParticleView& p : f.particles) {
    const Rgb c = def_.colour_by == Colouring::speed ? speed_colour(p.speed(), def_.speed_max_m_s) : state_colour(p.state);
    cairo_new_path(cr);
    cairo_arc(cr, p.x, p.y, p.radius - outline / 2, 0, 2 * M_PI);
    set_source(cr, c);
    cairo_fill_preserve(cr);
    cairo_set_source_rgba(cr, 0, 0, 0, 0.45);
    cairo_stroke(cr);
  }
  // A stopped flow: ring the arch's spheres whatever the colouring.
  if (!f.clogged || def_.colour_by == Colouring::state) return;
  set_source(cr, state_colour(ParticleState::arch));
  cairo_set_line_width(cr, 2 * outline);
  for (const ParticleView& p : f.particles) {
    if (p.state != ParticleState::arch) continue;
    cairo_new_path(cr);
    cairo_arc(cr, p.x, p.y, p.radius, 0, 2 * M_PI);
    cairo_stroke(cr);
  }
}

void TopView::draw_caption(cairo_t* cr, const FrameState& f) const {
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, 13);
  cairo_set_source_rgb(cr, 0, 0, 0);
  const std::string line1 = fmt::format("{} ({})", def_.title.empty() ? sc_.def.name : def_.title, f.model);
  std::string line2 = fmt::format("t = {:.2f} s   passed {}   J = {:.1f} /s   clogs {}", f.t, f.passed, f.j_so_far(),
                                  f.clogs);
  if (f.clogged) line2 += f.arch_on_obstruction ? "   CLOGGED: arch on obstruction" : "   CLOGGED";
  cairo_move_to(cr, kMarginPx, 17);
  cairo_show_text(cr, line1.c_str());
  cairo_move_to(cr, kMarginPx, 36);
  cairo_show_text(cr, line2.c_str());
}

void TopView::draw_legend(cairo_t* cr) const {
  const double x0 = board_left_ + board_w_ + 10;
  cairo_set_font_size(cr, 11);
  if (def_.colour_by == Colouring::speed) {
    const int bar_h = std::min(300, board_h_ - 40), bar_w = 16;
    const double y0 = board_top_ + 20;
    for (int i = 0; i < bar_h; ++i) {
      set_source(cr, speed_colour((bar_h - 1 - i) / static_cast<double>(bar_h - 1) * def_.speed_max_m_s,
                                  def_.speed_max_m_s));
      cairo_rectangle(cr, x0, y0 + i, bar_w, 1);
      cairo_fill(cr);
    }
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_move_to(cr, x0, y0 - 6);
    cairo_show_text(cr, "speed m/s");
    for (int k = 0; k <= 4; ++k) {
      cairo_move_to(cr, x0 + bar_w + 4, y0 + (bar_h - 1) * (1 - k / 4.0) + 4);
      cairo_show_text(cr, fmt::format("{:.2f}", def_.speed_max_m_s * k / 4).c_str());
    }
    return;
  }
  double y = board_top_ + 20;
  for (ParticleState s : {ParticleState::flowing, ParticleState::arch, ParticleState::stuck, ParticleState::passed}) {
    set_source(cr, state_colour(s));
    cairo_arc(cr, x0 + 6, y - 4, 6, 0, 2 * M_PI);
    cairo_fill(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_move_to(cr, x0 + 16, y);
    cairo_show_text(cr, to_string(s));
    y += 20;
  }
}

void TopView::write_png(const std::string& path) const {
  const std::string tmp = path + ".tmp";
  if (cairo_surface_write_to_png(surface_, tmp.c_str()) != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error("cannot write PNG " + path);
  std::filesystem::rename(tmp, path);
}

}  // namespace gapflow
