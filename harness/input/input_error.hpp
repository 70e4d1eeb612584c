// The one error type for bad input (case files, meshes, command line). Its message is a single
// line that names the file, the key or line, and what is allowed; `ricochet` prints it and
// exits with status 2 before writing anything.
#pragma once

#include <ostream>
#include <stdexcept>
#include <string>
#include <string_view>

namespace ricochet {

struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A message as one line: a line break or other control character (e.g. from the text of a
// TOML syntax error that quotes what it saw) is written as an escape, \n, \t or \xNN.
inline std::string one_line(std::string_view text) {
  static const char* hex = "0123456789abcdef";
  std::string out;
  out.reserve(text.size());
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '\n') out += "\\n";
    else if (c == '\r') out += "\\r";
    else if (c == '\t') out += "\\t";
    else if (c < 0x20 || c == 0x7f) out += std::string("\\x") + hex[c >> 4] + hex[c & 15];
    else out += ch;
  }
  return out;
}

// The exit statuses of every command, in one place: runs body() and returns its status; an
// InputError becomes the line "ricochet: MESSAGE" (one_line()) on `err` and status 2 (bad input, nothing
// written), any other exception "ricochet: error: MESSAGE" and status 1.
template <class Body>
int command_status(std::ostream& err, Body&& body) {
  try {
    return body();
  } catch (const InputError& e) {
    err << "ricochet: " << one_line(e.what()) << '\n';
    return 2;
  } catch (const std::exception& e) {
    err << "ricochet: error: " << one_line(e.what()) << '\n';
    return 1;
  }
}

}  // namespace ricochet
