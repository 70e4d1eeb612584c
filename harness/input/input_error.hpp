// The one error type for bad input (case files, meshes, command line). Its message is a single
// line that names the file, the key or line, and what is allowed; `ricochet` prints it and
// exits with status 2 before writing anything.
#pragma once

#include <ostream>
#include <stdexcept>
#include <string>

namespace ricochet {

struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The exit statuses of every command, in one place: runs body() and returns its status; an
// InputError becomes the line "ricochet: MESSAGE" on `err` and status 2 (bad input, nothing
// written), any other exception "ricochet: error: MESSAGE" and status 1.
template <class Body>
int command_status(std::ostream& err, Body&& body) {
  try {
    return body();
  } catch (const InputError& e) {
    err << "ricochet: " << e.what() << '\n';
    return 2;
  } catch (const std::exception& e) {
    err << "ricochet: error: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace ricochet
