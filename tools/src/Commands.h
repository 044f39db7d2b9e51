#pragma once
/// The `hapto` command's subcommands: each file adds its own to the app.

#include "hapto/scenes/Scene.h"

#include <CLI/CLI.hpp>

#include <string>

namespace hapto::cli {

/// `hapto scene ...`: generators and scene information. [control]
void addSceneCommands(CLI::App& app);

/// Loads `path`, or the embedded default scene when it is empty. Throws InputError. [control]
Scene loadSceneOrDefault(const std::string& path);

/// Parses a non-negative count such as "1000000" or "1e6"; throws InputError naming the option.
std::size_t parseCount(const std::string& text, const std::string& option);

} // namespace hapto::cli
