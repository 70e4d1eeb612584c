// Parameter checks shared by the mesh generators (mesh_generators.cpp, mesh_generators3.cpp):
// one-line InputError messages naming the generator and the parameter.
#pragma once

#include <cmath>
#include <sstream>
#include <string>

#include "harness/input/input_error.hpp"

namespace ricochet::generator_checks {

// Largest node count a generator builds; keeps indices in int and memory bounded.
inline constexpr long long max_nodes = 100'000'000;

[[noreturn]] inline void fail(const std::string& message) { throw InputError(message); }

// A number as a message shows it (the stream's default, 6 significant digits).
inline std::string str(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

inline void require_positive(const char* gen, const char* name, double v) {
  if (!std::isfinite(v) || v <= 0.0)
    fail(std::string(gen) + ": " + name + " must be finite and > 0 (got " + str(v) + ")");
}

}  // namespace ricochet::generator_checks
