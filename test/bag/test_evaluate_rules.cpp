// Rules evaluate_bag's scores and alignment obey whatever the method and the motion: a relative
// rotation error over a window is at most the sum of the errors at its two ends (the triangle
// inequality of the rotation angle), and Wahba's fit is a proper rotation (docs/bag_tools.md:
// the mount q_ST, a rotation, never a mirror).
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "../../src/tools/alignment.h"
#include "scene_bags.h"

namespace ap = attitude_propagator;
using namespace bagtest;

namespace {

using Row = std::vector<std::pair<std::string, std::string>>;

std::map<std::string, Row> evaluateRows(const TempDir& dir, const std::string& arguments,
                                        RunResult& result) {
  result = run(kEvaluateCore + " " + dir.file("in.bag") + " --csv " + dir.file("eval") +
               " --no-progress " + arguments);
  std::map<std::string, Row> rows;
  if (result.status != 0) return rows;
  for (const Row& row : readCsv(dir.file("eval.csv"))) rows[field(row, "method")] = row;
  return rows;
}

double number(const Row& row, const char* column) { return std::stod(field(row, column)); }

}  // namespace

// A tumbling triaxial body (its rotations about changing axes do not commute, so a relative
// rotation taken on the wrong side differs from the right one by up to the whole rotation):
// q_a, q_c the estimates and p_a, p_c the truths at a window's ends, the relative error
// angle((p_a^-1 p_c), (q_a^-1 q_c)) <= angle(p_a, q_a) + angle(p_c, q_c) <= 2 max_error, for
// every method, the exact ones (1e-9) and the first-order ones alike; the windows are filled.
TEST(EvaluateRules, RelativeErrorAtMostTheErrorsAtTheWindowsEnds) {
  TempDir dir;
  SceneBag scene;
  scene.motion = tumbling();
  scene.duration = 12.0;
  writeSceneBag(dir.file("in.bag"), scene);
  RunResult r;
  const auto rows = evaluateRows(dir, "--truth /truth --offset 0 --mount 0 0 0 1", r);
  ASSERT_EQ(r.status, 0) << r.output;
  ASSERT_GE(rows.size(), 4u) << r.output;
  for (const auto& [method, row] : rows) {
    const double bound = 2.0 * number(row, "max_error_rad") + 1e-12;
    for (const char* column : {"rpe_1s_max_rad", "rpe_10s_max_rad"}) {
      const double e = number(row, column);
      EXPECT_TRUE(std::isfinite(e)) << method << " " << column;
      EXPECT_LE(e, bound) << method << " " << column;
    }
  }
}

// Rates about two axes only (the vectors b_i in the xy plane) and a_i = R b_i with R a turn of
// 2.5 rad about x, which takes the plane's normal z to a direction with cos 2.5 < 0 along z:
// the sum a_i b_i^T alone has a zero singular value, and its nearest orthogonal matrix may be a
// mirror. The fit must be R itself: the only rotation that maps the plane so.
TEST(EvaluateRules, WahbaFitIsTheRotationNotItsMirror) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(2.5, Eigen::Vector3d::UnitX()).toRotationMatrix();
  std::vector<Eigen::Vector3d> a, b;
  for (int i = 0; i < 12; ++i) {
    const double angle = 2.0 * M_PI * i / 12.0;
    b.emplace_back(std::cos(angle), std::sin(angle), 0.0);
    a.push_back(R * b.back());
  }
  const Eigen::Matrix3d fit = ap::tools::wahba(a, b);
  EXPECT_NEAR(fit.determinant(), 1.0, 1e-9);
  EXPECT_LT((fit - R).norm(), 1e-6) << fit;
}
