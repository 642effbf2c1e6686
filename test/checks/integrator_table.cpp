// Prints the integrator table's names for test/checks/integrator_lists.sh, one row a line in
// the table's order (`auto` first): the name, then the models it drives (kinematic, dynamic),
// space-separated. Reads only the core's API (integrator.h).
#include <iostream>

#include "attitude_propagator/numerics/integrator.h"

int main() {
  namespace ap = attitude_propagator;
  for (const ap::IntegratorInfo& row : ap::integratorTable()) {
    std::cout << row.name;
    if (ap::supportsKinematic(row.id)) std::cout << " kinematic";
    if (ap::supportsDynamic(row.id)) std::cout << " dynamic";
    std::cout << '\n';
  }
  return 0;
}
