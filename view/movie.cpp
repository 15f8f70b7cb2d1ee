#include "view/movie.hpp"

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <sstream>
#include <stdexcept>
#include <sys/wait.h>
#include <unistd.h>

namespace gapflow {

namespace {

std::string shell_quoted(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

}  // namespace

std::string find_on_path(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    const std::filesystem::path candidate = std::filesystem::path(dir.empty() ? "." : dir) / program;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
  }
  return "";
}

void require_ffmpeg() {
  if (find_on_path("ffmpeg").empty())
    throw std::invalid_argument(
        "--movie needs ffmpeg, which is not on PATH: install Debian's package (apt-get install ffmpeg) or drop --movie");
}

MovieEncoder::MovieEncoder(std::string path, int width, int height, double fps)
    : path_(std::move(path)), partial_(path_ + ".partial"), width_(width), height_(height) {
  if (width % 2 || height % 2) throw std::logic_error("movie frames must have even sizes");
  if (!(fps > 0)) throw std::invalid_argument(fmt::format("--fps = {} must be > 0", fps));
  require_ffmpeg();
  // A dead ffmpeg must surface as a failed write (EPIPE), not kill gapflow.
  std::signal(SIGPIPE, SIG_IGN);
  const std::string cmd = fmt::format(
      "ffmpeg -nostdin -hide_banner -loglevel error -y -f rawvideo -pix_fmt bgra -s {}x{} -framerate {} -i - "
      "-an -c:v libx264 -preset veryfast -pix_fmt yuv420p -movflags +faststart -f mp4 {}",
      width, height, fps, shell_quoted(partial_));
  pipe_ = ::popen(cmd.c_str(), "w");
  if (!pipe_) throw std::runtime_error("cannot start ffmpeg");
}

MovieEncoder::~MovieEncoder() {
  if (!pipe_) return;
  ::pclose(pipe_);
  std::error_code ignored;
  std::filesystem::remove(partial_, ignored);
}

void MovieEncoder::add_frame(const unsigned char* bgra, int stride) {
  const size_t row = static_cast<size_t>(width_) * 4;
  for (int r = 0; r < height_; ++r)
    if (std::fwrite(bgra + static_cast<size_t>(r) * static_cast<size_t>(stride), 1, row, pipe_) != row)
      throw std::runtime_error("ffmpeg stopped reading frames (see its message above)");
  ++frames_;
}

void MovieEncoder::finish() {
  const int status = ::pclose(pipe_);
  pipe_ = nullptr;
  if (status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::error_code ignored;
    std::filesystem::remove(partial_, ignored);
    throw std::runtime_error(fmt::format("ffmpeg failed (status {}) writing {}", status, path_));
  }
  std::filesystem::rename(partial_, path_);
}

}  // namespace gapflow
