#include "app/cmd_serve.hpp"
#include <CLI/CLI.hpp>
namespace gapflow {
struct ServeCommand::Options { CLI::App* cmd = nullptr; };
ServeCommand::ServeCommand(CLI::App& app) : o_(std::make_unique<Options>()) {}
ServeCommand::~ServeCommand() = default;
std::optional<int> ServeCommand::run() const { return std::nullopt; }
}
