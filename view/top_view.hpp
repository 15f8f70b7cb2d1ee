// The top view of the board drawn with Cairo (libcairo2-dev): walls, the
// obstruction where the shaking has it, every sphere at its true size coloured by
// speed (with a colour bar) or by state, the gap line, and a caption with the
// time, the crossings, J so far and the clogs. Used for PNG snapshots, movie
// frames and the report pictures; the pixels stay in memory (movie frames are
// piped to ffmpeg, never written to disk).
#pragma once

#include "view/frame.hpp"

#include <memory>
#include <string>

typedef struct _cairo_surface cairo_surface_t;
typedef struct _cairo cairo_t;

namespace gapflow {

enum class Colouring { speed, state };
Colouring parse_colouring(const std::string& name);  // "speed" | "state"; throws std::invalid_argument

struct TopViewDef {
  Colouring colour_by = Colouring::speed;
  double px_per_mm = 1.0;        // px per mm of board (1 px/mm: a 1.55k-sphere board is ~400 x 1130 px)
  double speed_max_m_s = 0.5;    // m/s, top of the colour bar (faster spheres are drawn in its top colour)
  double below_gap_mm = 60.0;    // mm of board drawn below the gap line (passed spheres)
  std::string title;             // first caption line (e.g. the scenario name)
};

struct Rgb {
  unsigned char r = 0, g = 0, b = 0;
};

// Colours shared by every view (the live page uses the same values).
Rgb speed_colour(double speed_m_s, double speed_max_m_s);  // viridis, clamped to [0, max]
Rgb state_colour(ParticleState s);
Rgb wall_colour();
Rgb obstruction_colour();
Rgb board_colour();

class TopView {
 public:
  TopView(const CompiledScenario& sc, TopViewDef def);
  ~TopView();
  TopView(const TopView&) = delete;
  TopView& operator=(const TopView&) = delete;

  int width() const { return width_; }    // px, even (movie encoders need even sizes)
  int height() const { return height_; }  // px, even

  // Draw one frame (replaces the previous picture).
  void draw(const FrameState& frame);
  // Write the current picture as PNG, atomically (a temporary file renamed).
  void write_png(const std::string& path) const;

  // The pixel (column, row) of a board point (m, plane frame), and its colour.
  struct Pixel {
    int col = 0, row = 0;
  };
  Pixel to_pixel(Vec2 m) const;
  Rgb colour_at(Pixel p) const;
  // Rows of BGRA bytes (Cairo's ARGB32 on little-endian machines) for encoders.
  const unsigned char* data() const;
  int stride() const;  // bytes per row

 private:
  void draw_board(cairo_t* cr, const FrameState& f) const;
  void draw_particles(cairo_t* cr, const FrameState& f) const;
  void draw_caption(cairo_t* cr, const FrameState& f) const;
  void draw_legend(cairo_t* cr) const;

  const CompiledScenario& sc_;
  TopViewDef def_;
  double scale_ = 1;                 // px per m
  double x_min_ = 0, y_max_ = 0;     // m, the board's top-left corner in the picture
  int board_left_ = 0, board_top_ = 0, board_w_ = 0, board_h_ = 0;  // px
  int width_ = 0, height_ = 0;
  cairo_surface_t* surface_ = nullptr;
};

}  // namespace gapflow
