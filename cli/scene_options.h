// Command-line options that change a scene as it is loaded (shared by simulate, plan, replay, run
// and bench table1).
#pragma once
#include <CLI/CLI.hpp>
#include <string>

#include "squeeze/fem/scene.h"

namespace squeeze::cli {

/// Adds `--integrator NAME` (the registered integrators; default: the scene's `integrator` key).
void add_integrator_option(CLI::App* cmd, std::string& integrator);

/// load_scene, then the integrator override if not empty. Throws InputError ("--integrator x: …").
fem::Scene load_scene_with(const std::string& file, const std::string& integrator);

}  // namespace squeeze::cli
