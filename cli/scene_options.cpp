#include "scene_options.h"

#include "squeeze/common/error.h"
#include "squeeze/fem/integrator.h"

namespace squeeze::cli {

void add_integrator_option(CLI::App* cmd, std::string& integrator) {
  std::string names;
  for (const std::string& n : fem::integrator_names()) names += (names.empty() ? "" : ", ") + n;
  cmd->add_option("--integrator", integrator,
                  "Time integrator: " + names + " (default: the scene's \"integrator\" key, itself \"implicit\" when absent; \"verlet\" is the paper's explicit step; scenes/README.md)");
}

fem::Scene load_scene_with(const std::string& file, const std::string& integrator) {
  fem::Scene scene = fem::load_scene(file);
  if (!integrator.empty()) {
    try {
      fem::make_integrator(integrator);
    } catch (const InputError& e) {
      throw InputError("--integrator " + integrator + ": " + e.what());
    }
    scene.integrator = integrator;
  }
  return scene;
}

}  // namespace squeeze::cli
