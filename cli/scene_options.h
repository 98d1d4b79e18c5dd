// Command-line options that change a scene as it is loaded (shared by simulate, plan, replay, run
// and bench table1), and the warnings of `squeeze check` that they print.
#pragma once
#include <CLI/CLI.hpp>
#include <optional>
#include <string>

#include "squeeze/fem/scene.h"

namespace squeeze {
class Progress;
}

namespace squeeze::cli {

/// Adds `--integrator NAME` (the registered integrators; default: the scene's `integrator` key).
void add_integrator_option(CLI::App* cmd, std::string& integrator);

/// load_scene, then the integrator override if not empty. Throws InputError ("--integrator x: …").
fem::Scene load_scene_with(const std::string& file, const std::string& integrator);

// Defined in cmd_check.cpp:
/// The expansion volume limit of a scene with one deformable robot (planner.max_volume_change, the
/// planner block validated: throws InputError on a bad one); empty without such a robot.
std::optional<double> scene_volume_limit(const fem::SceneWorld& w);
/// `squeeze check`'s warnings on an already built scene, one spdlog::warn line each ("SCENE: …"),
/// nothing (and no work) with -q. Used by simulate, plan and run before they start.
///   settle    seconds of the check's settle (plan::SceneCheckOptions::settle; 0: none — simulate,
///             whose own run is that settle: it stops on divergence and metrics.csv has the volumes)
///   progress  shows the settle as a stage (it costs as much as simulating that long), or null
void print_scene_warnings(const fem::SceneWorld& w, std::optional<double> max_volume_change, double settle = 0.1,
                          Progress* progress = nullptr);

}  // namespace squeeze::cli
