#include "common/text_file.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace gapflow {

std::optional<std::string> read_text_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_file_atomically(const std::filesystem::path& path, const std::function<void(std::ostream&)>& write) {
  const std::filesystem::path tmp = path.string() + ".partial";
  {
    std::ofstream out(tmp);
    if (!out) throw std::runtime_error("cannot write " + tmp.string());
    write(out);
    if (!out.flush()) throw std::runtime_error("error while writing " + tmp.string());
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace gapflow
