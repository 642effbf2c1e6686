// Shared by the fuzz targets: a forward byte reader that turns libFuzzer's bytes into the values
// the core is fed (extreme doubles on purpose), and the oracle's checks.
//
// The decoding is part of the regression inputs in test/fuzz/regressions/: changing what a byte
// means changes what those files test. Append new choices at the end of a table instead of
// reordering, and regenerate the seeds (make_seeds.py) when the format changes.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <typeinfo>
#include <vector>

#include <cxxabi.h>

#include <Eigen/Geometry>

#include "attitude_propagator/numerics/integrator.h"

namespace attitude_propagator_fuzz {

/// Doubles that break numerics: signed zeros, the edges of the double range, squares that
/// overflow (> 1e154), denormals, NaN and infinities, and ordinary magnitudes in between.
inline double specialValue(std::uint8_t i) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  static const double kTable[] = {
      0.0,
      -0.0,
      1.0,
      -1.0,
      0.5,
      1e-3,
      1e-2,
      0.1,
      10.0,
      100.0,
      1e3,
      1e6,
      1e12,
      1e100,
      1e154,
      1e155,
      1e200,
      1e300,
      -1e300,
      1e-12,
      1e-100,
      1e-300,
      M_PI,
      9007199254740992.0,
      1.7e9,
      -1e12,
      -1e200,
      std::numeric_limits<double>::max(),
      std::numeric_limits<double>::min(),
      std::numeric_limits<double>::denorm_min(),
      -std::numeric_limits<double>::denorm_min(),
      std::numeric_limits<double>::quiet_NaN(),
      -std::numeric_limits<double>::quiet_NaN(),
      kInf,
      -kInf,
      2.0,
      3.0,
      0.05,
      20.0,
      4.0,
  };
  return kTable[i % (sizeof(kTable) / sizeof(kTable[0]))];
}

/// Reads the input front to back; past its end every byte reads as zero, so any input decodes.
class ByteReader {
 public:
  ByteReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  bool exhausted() const { return pos_ >= size_; }

  /// Where the next byte is read (for the trace of an input's choices).
  std::size_t position() const { return pos_; }

  std::uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }

  /// 0 .. n-1.
  unsigned choice(unsigned n) { return byte() % n; }

  bool flag() { return (byte() & 1) != 0; }

  double rawDouble() {
    std::uint64_t bits = 0;
    for (int i = 0; i < 8; ++i) bits |= static_cast<std::uint64_t>(byte()) << (8 * i);
    double x;
    std::memcpy(&x, &bits, sizeof x);
    return x;
  }

  /// A value of any kind: a special one, a moderate one (|x| < 33, step 1e-3), any bit
  /// pattern, or a special one scaled by a factor in [-1, 1].
  double value() {
    switch (byte() % 4) {
      case 0:
        return specialValue(byte());
      case 1: {
        const auto hi = static_cast<std::uint16_t>(byte() << 8);
        const auto bits = static_cast<std::uint16_t>(hi | byte());
        return static_cast<std::int16_t>(bits) / 1000.0;
      }
      case 2:
        return rawDouble();
      default: {
        const double scale = specialValue(byte());
        return scale * (static_cast<std::int8_t>(byte()) / 127.0);
      }
    }
  }

  Eigen::Vector3d vector3() {
    const double x = value(), y = value(), z = value();
    return {x, y, z};
  }

  /// Eigen's (w, x, y, z) order.
  Eigen::Quaterniond quaternion() {
    const double w = value(), x = value(), y = value(), z = value();
    return Eigen::Quaterniond(w, x, y, z);
  }

  /// The next stamp after `last`: mostly forward by a sensor period, but also repeated,
  /// slightly and far backward, across max_dt, by a denormal, or anywhere at all.
  double stamp(double last) {
    static const double kSteps[] = {1e-3, 5e-3, 1e-2, 0.1, 0.5, 1.0, 1.0 + 1e-9, 2.0};
    switch (byte() % 8) {
      case 0:
        return last + kSteps[byte() % 8];
      case 1:
        return last;
      case 2:
        return last - 0.5;
      case 3:
        return last - 5.0;
      case 4:
        return last + value();
      case 5:
        return value();
      case 6:
        return byte() % 2 ? std::nextafter(last, std::numeric_limits<double>::infinity())
                          : last + std::numeric_limits<double>::denorm_min();
      default:
        return last + 1e-3;
    }
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

/// The integrators by code: an input names its integrator by one byte, an index into this
/// list (a byte past its end wraps around). The code is the method's row in the core's table
/// (integrator.h): rows are appended, never inserted, reordered or removed, so an input whose
/// byte is below the list's length means the same method whatever the table holds later.
/// make_seeds.py's NAMES reads the same rows from the table's source (test/checks/
/// integrator_lists.sh checks it against the built table); the regression inputs named after a
/// method are checked to read that method from such a byte (scripts/fuzz.sh --regressions,
/// through FUZZ_TRACE's "integrator code" line).
inline const std::vector<std::string>& integratorCodes() {
  static const std::vector<std::string> codes = attitude_propagator::integratorNames();
  return codes;
}

/// With FUZZ_TRACE set in the environment, prints the calls an input decodes to (for reading a
/// finding: FUZZ_TRACE=1 fuzz_<target> FILE).
inline bool tracing() {
  static const bool on = std::getenv("FUZZ_TRACE") != nullptr;
  return on;
}

#define FUZZ_TRACE(...)                  \
  do {                                   \
    if (tracing()) {                     \
      std::fprintf(stderr, __VA_ARGS__); \
      std::fputc('\n', stderr);          \
    }                                    \
  } while (false)

/// Reads an integrator's code byte (integratorCodes()) and traces it with its position:
/// "integrator code <byte> at <offset>: <name>".
inline std::string readIntegratorCode(ByteReader& in, const std::vector<std::string>& names) {
  const std::size_t at = in.position();
  const unsigned code = in.byte();
  const std::string& name = names[code % names.size()];
  FUZZ_TRACE("integrator code %u at %zu: %s", code, at, name.c_str());
  return name;
}

/// Reports a broken invariant and aborts, which libFuzzer records as a crash with the input.
[[noreturn]] inline void fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "\nFUZZ ORACLE: %s: %s\n", what, detail.c_str());
  std::fflush(stderr);
  std::abort();
}

inline std::string describe(const Eigen::Quaterniond& q) {
  char text[160];
  std::snprintf(text, sizeof text, "q (w x y z) = (%.17g, %.17g, %.17g, %.17g), |q| = %.17g", q.w(),
                q.x(), q.y(), q.z(), q.norm());
  return text;
}

inline std::string describe(const Eigen::Vector3d& v) {
  char text[120];
  std::snprintf(text, sizeof text, "(%.17g, %.17g, %.17g)", v.x(), v.y(), v.z());
  return text;
}

/// The orientation is a finite unit quaternion: | |q| - 1 | <= 1e-9 (renormalised states sit
/// within a few ulp of 1; 1e-9 leaves room for none of the failures, a zero or NaN q).
inline void requireUnit(const Eigen::Quaterniond& q, const char* after) {
  if (!q.coeffs().allFinite() || !(std::abs(q.norm() - 1.0) <= 1e-9)) {
    fail(after, "orientation is not a finite unit quaternion: " + describe(q));
  }
}

inline void requireFinite(const Eigen::Vector3d& v, const char* what, const char* after) {
  if (!v.allFinite()) fail(after, std::string(what) + " is not finite: " + describe(v));
}

inline void requireFinite(double x, const char* what, const char* after) {
  if (!std::isfinite(x)) fail(after, std::string(what) + " is not finite: " + std::to_string(x));
}

inline std::string typeName(const std::exception& e) {
  int status = 0;
  char* name = abi::__cxa_demangle(typeid(e).name(), nullptr, nullptr, &status);
  const std::string result = status == 0 ? name : typeid(e).name();
  std::free(name);
  return result;
}

/// Runs f; std::invalid_argument is the documented refusal (returns false), any other exception
/// is a finding.
template <class F>
bool acceptedBy(const char* call, F&& f) {
  try {
    f();
    return true;
  } catch (const std::invalid_argument&) {
    return false;
  } catch (const std::exception& e) {
    fail(call, "threw " + typeName(e) + ": " + e.what());
  } catch (...) {
    fail(call, "threw a non-standard exception");
  }
}

/// Runs f, which must not throw at all.
template <class F>
auto noThrow(const char* call, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const std::exception& e) {
    fail(call, "threw " + typeName(e) + ": " + e.what());
  } catch (...) {
    fail(call, "threw a non-standard exception");
  }
}

}  // namespace attitude_propagator_fuzz
