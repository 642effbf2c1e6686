// Rows of the benchmark CSV files (docs/design.md §8). Quantities that do not apply to a scene
// (the invariants of a kinematic scene, the cost of a stability run) are written empty.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>

namespace bench {

/// One (scene, method, step) result of the work-precision sweep or of the stability map.
struct Result {
  std::string scene;
  std::string method;
  bool is_auto = false;    ///< the method `auto` resolves to for this scene (from the core)
  double dt = NAN;         ///< s, the step (dopri5: the output step)
  double omega_dt = NAN;   ///< largest |w| of the scene times dt (rad per step)
  double tolerance = NAN;  ///< dopri5 only
  long steps = 0;
  double ns_per_step = NAN;         ///< median over repetitions, see timing.h
  double err_rad = NAN;             ///< largest rotation angle to the truth along the path
  double final_err_rad = NAN;       ///< rotation angle to the truth at the end
  double energy_rel_drift = NAN;    ///< largest |E - E0| / E0 along the path
  double momentum_rel_drift = NAN;  ///< largest ||M| - |M0|| / |M0| along the path
  double norm_err = NAN;            ///< largest ||q| - 1| of a step before renormalisation
  std::string status = "ok";        ///< ok, nonfinite, norm_lost, wrong_side, diverged
  double jitter_s = NAN;            ///< stability map: receipt jitter of the stamps (s, RMS)
};

inline const char* csvHeader() {
  return "scene,method,auto,dt,omega_dt,tolerance,steps,ns_per_step,err_rad,final_err_rad,"
         "energy_rel_drift,momentum_rel_drift,norm_err,status,jitter_s\n";
}

/// %.6g, or empty for NaN (not applicable).
inline std::string field(double v) {
  if (std::isnan(v)) return "";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

inline void writeRow(std::FILE* out, const Result& r) {
  std::fprintf(out, "%s,%s,%d,%.9g,%.6g,%s,%ld,%s,%s,%s,%s,%s,%s,%s,%s\n", r.scene.c_str(),
               r.method.c_str(), r.is_auto ? 1 : 0, r.dt, r.omega_dt, field(r.tolerance).c_str(),
               r.steps, field(r.ns_per_step).c_str(), field(r.err_rad).c_str(),
               field(r.final_err_rad).c_str(), field(r.energy_rel_drift).c_str(),
               field(r.momentum_rel_drift).c_str(), field(r.norm_err).c_str(), r.status.c_str(),
               field(r.jitter_s).c_str());
  std::fflush(out);
}

}  // namespace bench
