// The one error type for bad input (case files, meshes, command line). Its message is a single
// line that names the file, the key or line, and what is allowed; `ricochet` prints it and
// exits with status 2 before writing anything.
#pragma once

#include <stdexcept>
#include <string>

namespace ricochet {

struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace ricochet
