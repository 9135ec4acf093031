// plantsim: the emulated generator set behind the rig's Modbus and CAN links
// (DESIGN.md sections 4 and 7). Everything lives in plantsim_serve and plantsim_model.
#include "plantsim/plant/config.hpp"
#include "plantsim/plant/linearise.hpp"
#include "plantsim/plant/plant.hpp"
#include "plantsim/serve/app.hpp"

int main(int argc, char** argv) {
  const plantsim::serve::PlantHooks hooks{
      plantsim::make_plant,
      [](const plantsim::PlantOptions& options, const std::filesystem::path& file) {
        plantsim::write_tf_json(plantsim::linearise(options), file);
      },
      [](const plantsim::PlantOptions& options) {
        return plantsim::to_toml(plantsim::resolve(options).params,
                                 "Plant parameters: key = value  # [unit] meaning (range)");
      }};
  return plantsim::serve::plantsim_main(argc, argv, hooks);
}
