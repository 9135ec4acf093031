// plantsim serving the linear test plant: the same program as build/bin/plantsim with a plant
// whose response is known in closed form, so the protocol tests do not depend on the
// generator-set model's numbers.
#include "plantsim/serve/app.hpp"
#include "tests/integration/serve/linear_plant.hpp"

int main(int argc, char** argv) {
  return plantsim::serve::plantsim_main(argc, argv,
                                        {plantsim::testing::make_linear_plant, nullptr, nullptr});
}
