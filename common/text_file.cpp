#include "common/text_file.hpp"

#include "common/input_bounds.hpp"

#include <fmt/format.h>

#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <system_error>

namespace gapflow {

namespace fs = std::filesystem;

FileError::FileError(const fs::path& path, std::string reason)
    : std::invalid_argument(fmt::format("{}: {}", path.string(), reason)), reason_(std::move(reason)) {}

namespace {

// What a non-regular file is, for messages.
const char* kind_of(const struct stat& st) {
  if (S_ISDIR(st.st_mode)) return "a directory";
  if (S_ISCHR(st.st_mode)) return "a character device";
  if (S_ISBLK(st.st_mode)) return "a block device";
  if (S_ISFIFO(st.st_mode)) return "a FIFO (named pipe)";
  if (S_ISSOCK(st.st_mode)) return "a socket";
  return "not a regular file";
}

std::string errno_text(int e) { return e == ENOENT ? "no such file" : std::strerror(e); }

}  // namespace

std::string read_input_file(const fs::path& file, const std::string& what) {
  struct stat st {};
  if (::stat(file.c_str(), &st) != 0) throw FileError(file, errno_text(errno));
  // Pipes are read (process substitution, <(...)); devices and directories never are.
  if (!S_ISREG(st.st_mode) && !S_ISFIFO(st.st_mode))
    throw FileError(file, fmt::format("is {}, not a {}", kind_of(st), what));
  std::ifstream in(file, std::ios::binary);
  if (!in) throw FileError(file, errno_text(errno));
  std::string text;
  char buf[65536];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    text.append(buf, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxInputFileBytes)
      throw FileError(file, fmt::format("is larger than {} MiB: not a {}", kMaxInputFileBytes >> 20, what));
  }
  if (in.bad()) throw FileError(file, "read error");
  return text;
}

std::optional<std::string> read_text_file(const fs::path& file) {
  try {
    return read_input_file(file, "text file");
  } catch (const FileError&) {
    return std::nullopt;
  }
}

void check_output_file(const fs::path& path) {
  if (path.empty()) throw FileError(path, "empty output path");
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) {
    if (!S_ISREG(st.st_mode))
      throw FileError(path, fmt::format("is {}: gapflow writes only regular files and will not replace it",
                                        kind_of(st)));
  } else if (errno != ENOENT) {
    throw FileError(path, std::strerror(errno));
  }
  const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) throw FileError(path, fmt::format("the folder {} does not exist", folder.string()));
  // The only sure test of "can I create a file here" is to create one.
  const fs::path probe = path.string() + ".partial";
  std::FILE* f = std::fopen(probe.c_str(), "wb");
  if (!f) throw FileError(path, fmt::format("cannot create a file in {}: {}", folder.string(), std::strerror(errno)));
  std::fclose(f);
  fs::remove(probe, ec);
}

void write_file_atomically(const fs::path& path, const std::function<void(std::ostream&)>& write) {
  check_output_file(path);
  const fs::path tmp = path.string() + ".partial";
  std::error_code ec;
  try {
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) throw std::runtime_error(fmt::format("cannot write {}: {}", tmp.string(), std::strerror(errno)));
      write(out);
      out.flush();
      if (!out) throw std::runtime_error(fmt::format("error while writing {} (disk full?)", tmp.string()));
      out.close();
      if (!out) throw std::runtime_error(fmt::format("error while closing {} (disk full?)", tmp.string()));
    }
    fs::rename(tmp, path);
  } catch (...) {
    fs::remove(tmp, ec);  // never leave a partial file behind
    throw;
  }
}

std::optional<std::string> flush_stdout() {
  std::cout.flush();
  const bool cpp_ok = static_cast<bool>(std::cout);
  errno = 0;
  const bool c_ok = std::fflush(stdout) == 0 && !std::ferror(stdout);
  if (cpp_ok && c_ok) return std::nullopt;
  return errno ? std::string(std::strerror(errno)) : std::string("write error");
}

void check_output_folder(const fs::path& dir) {
  std::error_code ec;
  const fs::file_status st = fs::status(dir, ec);
  if (fs::exists(st) && !fs::is_directory(st))
    throw FileError(dir, "is not a folder (output folders must be absent or folders)");
}

}  // namespace gapflow
