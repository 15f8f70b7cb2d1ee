// Whole-file reading and all-or-nothing writing, shared by every front end.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <ostream>
#include <string>

namespace gapflow {

// The file's bytes, or nothing if it cannot be opened.
std::optional<std::string> read_text_file(const std::filesystem::path& file);

// Write to "<path>.partial" and rename when complete: a reader never sees half a
// file, and an interrupted write leaves no file under the real name.
void write_file_atomically(const std::filesystem::path& path, const std::function<void(std::ostream&)>& write);

}  // namespace gapflow
