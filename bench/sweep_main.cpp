// bench_sweep: runs every integrator on the scenes of docs/design.md §8 over a sweep of step sizes
// and writes, into the output folder,
//   sweep.csv       work-precision: error and median cost per step for every (scene, method, dt)
//   stability.csv   error after a fixed time against |w| dt from 1e-3 to 10
//   invariants.csv  energy and |M| drift against time on a long free-body run
//   fixes.csv       late absolute fixes on a simulated gyro (test/core/simulated_gyro.h): the
//                   attitude error and its standard deviation against time, with and without
//                   the gyro bias estimate, and the bias estimate's error (every 0.5 s)
//   real_streams.csv  every kinematic method and `auto` on real gyro streams (point and
//                     averaged at 100-1000 Hz, mid- and start-stamped means, receipt stamps
//                     late by a latency, lost samples, noisy MEMS, on-chip filters, FIFO reads,
//                     a rate change) on the coning, tumbling, fast tumbling and vibration scenes
// Usage: bench_sweep [out_dir] [--quick] [--streams | --stability | --fixes]   (--quick: fewer
// repetitions, for a smoke test; --streams: only real_streams.csv; --stability: only
// stability.csv; --fixes: only fixes.csv)
#include <cstdio>
#include <cstring>
#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

#include "../test/core/simulated_gyro.h"
#include "csv.h"
#include "dynamic_sweep.h"
#include "kinematic_sweep.h"
#include "reference.h"

namespace {

struct Options {
  std::string out_dir = ".";
  bool streams_only = false;
  bool stability_only = false;
  bool fixes_only = false;
  bench::TimingOptions timing;
};

Options parse(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--streams") == 0) {
      options.streams_only = true;
    } else if (std::strcmp(argv[i], "--stability") == 0) {
      options.stability_only = true;
    } else if (std::strcmp(argv[i], "--fixes") == 0) {
      options.fixes_only = true;
    } else if (std::strcmp(argv[i], "--quick") == 0) {
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

std::vector<bench::DynamicScene> dynamicScenes() {
  return {bench::freeBodyScene(), bench::dzhanibekovScene(), bench::symmetricTopScene(),
          bench::torquedScene()};
}

// The scene of the fix tests (600 s, fixes at 5 Hz with 1 mrad noise, 150 ms late, fuse), with
// and without the bias estimate: every 0.5 s the body-frame attitude error Log(q_est^-1 q_true)
// and sqrt(P_B) per axis, the bias estimate's error and its standard deviation (deg/h).
void writeFixRuns(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) throw std::runtime_error("cannot write " + path);
  std::fputs(
      "run,t,err_x,err_y,err_z,sd_x,sd_y,sd_z,bias_err_x,bias_err_y,bias_err_z,"
      "bias_sd_x,bias_sd_y,bias_sd_z\n",
      f);
  for (bool estimate : {true, false}) {
    const char* run = estimate ? "bias_estimated" : "bias_not_estimated";
    long k = 0;
    const simulated_gyro::GyroRun result = simulated_gyro::simulateGyro(
        600.0, true, estimate, 0.0,
        [&](double t, const attitude_propagator::EngineState& s, const Eigen::Quaterniond& truth,
            const Eigen::Vector3d& bias) {
          if (k++ % 100 != 0) return;
          const Eigen::Vector3d e = attitude_propagator::logMap(s.q_WB.conjugate() * truth);
          const Eigen::Vector3d sd = s.P_B.diagonal().cwiseMax(0.0).cwiseSqrt();
          const double per = 1.0 / simulated_gyro::kDegPerHour;
          const Eigen::Vector3d be = per * (s.gyro_bias_estimate_B - bias);
          const Eigen::Vector3d bsd = per * s.gyro_bias_stddev_B;
          std::fprintf(f, "%s,%.3f,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e\n",
                       run, t, e.x(), e.y(), e.z(), sd.x(), sd.y(), sd.z(), be.x(), be.y(), be.z(),
                       bsd.x(), bsd.y(), bsd.z());
        });
    std::fprintf(stderr,
                 "bench: fixes (%s): rms after 60 s %.3g rad, mean NEES %.2f, bias error %.3g "
                 "deg/h at 120 s, %.3g deg/h at 600 s\n",
                 run, result.rms_after_60, result.mean_nees,
                 result.bias_error_120 / simulated_gyro::kDegPerHour,
                 result.bias_error_end / simulated_gyro::kDegPerHour);
  }
  std::fclose(f);
}

// The references judge everything else, so they are checked first against known answers:
// the constant torque from rest (docs/numerics.md §8) and Hairer-Lubich-Wanner's M(100).
bool checkReferences() {
  const double from_rest = bench::referenceSelfCheck();
  const auto scene = bench::freeBodyScene();
  const auto x100 = bench::referenceStates(scene.moments, scene.initial, {0, 0, 0}, {100.0});
  const Eigen::Vector3d M100 = scene.moments.cwiseProduct(x100.front().w_B);
  const double hlw =
      (M100 - Eigen::Vector3d(-0.177348313874983, -0.590418524333421, 0.787371285791935)).norm();
  std::fprintf(stderr, "bench: reference check: torque from rest %.2e rad, HLW M(100) %.2e\n",
               from_rest, hlw);
  return from_rest < 1e-12 && hlw < 1e-12;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Options options = parse(argc, argv);
    if (options.fixes_only) {
      writeFixRuns(options.out_dir + "/fixes.csv");
      return 0;
    }
    const auto scenes = kinematicScenes();
    for (const auto& scene : scenes) {
      if (!bench::checkClosedForm(scene)) return 1;
    }
    const std::vector<bench::KinematicScene> stream_scenes{
        bench::coningScene(), bench::tumblingScene(), bench::fastTumblingScene(),
        bench::vibrationScene()};
    for (const auto& scene : stream_scenes) {
      if (!bench::checkClosedForm(scene)) return 1;
    }
    if (!checkReferences()) return 1;
    if (!options.stability_only) {
      std::FILE* streams = std::fopen((options.out_dir + "/real_streams.csv").c_str(), "w");
      if (streams == nullptr) throw std::runtime_error("cannot write real_streams.csv");
      bench::runStreamSweep(stream_scenes, streams);
      std::fclose(streams);
    }
    if (options.streams_only) return 0;
    if (!options.stability_only) writeFixRuns(options.out_dir + "/fixes.csv");
    if (!options.stability_only) {
      std::FILE* sweep = openCsv(options.out_dir + "/sweep.csv");
      bench::runKinematicSweep(scenes, options.timing, sweep);
      auto dynamic = dynamicScenes();
      bench::runDynamicSweep(dynamic, options.timing, sweep);
      std::fclose(sweep);
    }

    std::FILE* stability = openCsv(options.out_dir + "/stability.csv");
    bench::runKinematicStability(bench::fastSpinScene(), 1.0, stability);
    bench::runDynamicStability(bench::freeBodyScene(), 100.0, stability);
    bench::runDynamicStability(bench::dzhanibekovScene(), 30.0, stability);
    std::fclose(stability);
    if (options.stability_only) return 0;

    std::FILE* invariants = std::fopen((options.out_dir + "/invariants.csv").c_str(), "w");
    std::fputs("method,dt,tolerance,t,energy_rel_drift,momentum_rel_drift,err_rad\n", invariants);
    bench::runInvariants(bench::freeBodyScene(), 0.1, 10000.0, 10.0, invariants);
    std::fclose(invariants);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_sweep: %s\n", e.what());
    return 1;
  }
  return 0;
}
