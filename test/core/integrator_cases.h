// The integrators under test, read from the core's table (integrator.h), and the bound every
// convergence test puts on a declared order: a new method joins the tests by its row.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "attitude_propagator/numerics/integrator.h"

namespace integrator_cases {

namespace ap = attitude_propagator;

/// The methods that drive `model` and whose row satisfies `keep`, in the table's order.
template <class Predicate>
std::vector<ap::Integrator> methodsWhere(ap::Model model, Predicate keep) {
  std::vector<ap::Integrator> methods;
  for (ap::Integrator m : ap::integratorsFor(model)) {
    if (keep(ap::integratorInfo(m))) methods.push_back(m);
  }
  return methods;
}

/// The methods that drive `model` and keep every property in `flags` (keeps::*).
inline std::vector<ap::Integrator> methodsKeeping(ap::Model model, unsigned flags) {
  return methodsWhere(
      model, [flags](const ap::IntegratorInfo& row) { return (row.keeps & flags) == flags; });
}

/// How far below its declared order p a method's measured order log2(e(h) / e(h/2)) may fall:
/// halving the step must divide the error by at least 2^(p - kOrderSlack) (3.5 for p = 2, 14
/// for p = 4).
constexpr double kOrderSlack = 0.2;
inline double minHalvingRatio(int order) { return std::exp2(order - kOrderSlack); }

/// Test names from the integrator names.
struct MethodName {
  std::string operator()(const ::testing::TestParamInfo<ap::Integrator>& info) const {
    return ap::integratorName(info.param);
  }
};

}  // namespace integrator_cases
