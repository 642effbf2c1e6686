// bench_sweep: runs every integrator on the scenes of DESIGN §7 over a sweep of step sizes and
// writes, into the output folder,
//   sweep.csv       work-precision: error and median cost per step for every (scene, method, dt)
//   stability.csv   error after a fixed time against |w| dt from 1e-3 to 10
//   invariants.csv  energy and |M| drift against time on a long free-body run
// Usage: bench_sweep [out_dir] [--quick]   (--quick: fewer repetitions, for a smoke test)
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "csv.h"
#include "kinematic_sweep.h"

namespace {

struct Options {
  std::string out_dir = ".";
  bench::TimingOptions timing;
};

Options parse(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      options.timing.rounds = 1;
      options.timing.min_chunk_ms = 0.0;
    } else {
      options.out_dir = argv[i];
    }
  }
  return options;
}

std::FILE* openCsv(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) throw std::runtime_error("cannot write " + path);
  std::fputs(bench::csvHeader(), f);
  return f;
}

std::vector<bench::KinematicScene> kinematicScenes() {
  return {bench::constantRateScene(), bench::coningScene(), bench::fastSpinScene()};
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Options options = parse(argc, argv);
    const auto scenes = kinematicScenes();
    for (const auto& scene : scenes) {
      if (!bench::checkClosedForm(scene)) return 1;
    }
    std::FILE* sweep = openCsv(options.out_dir + "/sweep.csv");
    std::FILE* stability = openCsv(options.out_dir + "/stability.csv");
    bench::runKinematicSweep(scenes, options.timing, sweep);
    bench::runKinematicStability(bench::fastSpinScene(), 1.0, stability);
    std::fclose(sweep);
    std::fclose(stability);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_sweep: %s\n", e.what());
    return 1;
  }
  return 0;
}
