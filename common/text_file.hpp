// Whole-file reading with bounds, and safe all-or-nothing writing, shared by every
// front end (run, check, study, report, export; later calibrate and twin).
//
// Reading: an input file must be a regular file (or a pipe) of at most
// kMaxInputFileBytes; a missing file, a directory or a device is refused with the
// reason, never read as an empty or endless text.
// Writing: the target is checked before any work is done (check_output_file), the
// bytes go to "<path>.partial" and are renamed over the target when complete, and the
// partial file is removed on any failure: a reader never sees half a file, and
// nothing but a regular file (or nothing) is ever replaced.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>

namespace gapflow {

// A path that cannot be used as asked (bad input: exit 2). what() = "<path>: <reason>".
class FileError : public std::invalid_argument {
 public:
  FileError(const std::filesystem::path& path, std::string reason);
  const std::string& reason() const { return reason_; }

 private:
  std::string reason_;
};

// The bytes of an input file; throws FileError saying why it cannot be one
// ("no such file", "is a directory, not a scenario file", "is larger than 4 MiB", ...).
// `what` names the expected content in messages, e.g. "scenario file".
std::string read_input_file(const std::filesystem::path& file, const std::string& what);

// The file's bytes, or nothing if it cannot be read as an input file (same bounds).
std::optional<std::string> read_text_file(const std::filesystem::path& file);

// Throws FileError unless `path` can be written by write_file_atomically: it is absent
// or a regular file (not a directory, FIFO, device or socket), and its folder exists
// and takes a new file. Call it before long work whose result goes there.
void check_output_file(const std::filesystem::path& path);

// Throws FileError unless `dir` can be an output folder: absent (it will be made) or a
// folder; a file or device named by mistake is refused, never written into or replaced.
void check_output_folder(const std::filesystem::path& dir);

// Write to "<path>.partial" and rename when complete (see above). Write errors (a
// full disk) throw std::runtime_error and leave neither the partial file nor a
// changed target.
void write_file_atomically(const std::filesystem::path& path, const std::function<void(std::ostream&)>& write);

// Flush standard output (C++ and C streams); the reason if anything written to it was
// lost (a full disk, a closed pipe), else nothing.
std::optional<std::string> flush_stdout();

}  // namespace gapflow
