// A movie of a run: frames (BGRA rows from TopView) are piped into Debian's
// ffmpeg and encoded to H.264/MP4 on the fly; no frame is ever written to disk.
// The file appears under its name only when ffmpeg finished cleanly
// (written to "<path>.partial", renamed at the end).
#pragma once

#include <cstdio>
#include <string>

namespace gapflow {

// The full path of an executable found on PATH, or "" if there is none.
std::string find_on_path(const std::string& program);

// Throws std::invalid_argument (exit 2) naming the package when ffmpeg is not installed.
void require_ffmpeg();

class MovieEncoder {
 public:
  // Starts ffmpeg; width and height in px (even), fps frames per second of movie.
  MovieEncoder(std::string path, int width, int height, double fps);
  ~MovieEncoder();  // an unfinished movie is discarded (ffmpeg stopped, partial file removed)
  MovieEncoder(const MovieEncoder&) = delete;
  MovieEncoder& operator=(const MovieEncoder&) = delete;

  // One frame: `height` rows of `width` BGRA pixels, `stride` bytes apart.
  void add_frame(const unsigned char* bgra, int stride);
  // Close the pipe, wait for ffmpeg and move the movie into place. Throws if ffmpeg failed.
  void finish();
  int frames() const { return frames_; }

 private:
  std::string path_, partial_;
  int width_, height_;
  int frames_ = 0;
  FILE* pipe_ = nullptr;
};

}  // namespace gapflow
