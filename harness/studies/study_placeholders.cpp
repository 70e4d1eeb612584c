#include "harness/studies/study_placeholders.hpp"

#include <cstdlib>
#include <system_error>

#include "harness/input/input_error.hpp"

namespace ricochet {

std::string expand_placeholders(const std::string& text, const Placeholders& v) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '{') {
      out += text[i];
      continue;
    }
    if (i + 1 < text.size() && text[i + 1] == '{') {
      out += '{';
      ++i;
      continue;
    }
    const std::size_t close = text.find('}', i);
    if (close == std::string::npos)
      throw InputError("\"" + text + "\": a '{' without its '}' (write {{ for a literal {)");
    const std::string name = text.substr(i + 1, close - i - 1);
    std::string sweeps;
    for (const auto& [n, dir] : v.sweeps) sweeps += (sweeps.empty() ? "" : ", ") + n;
    if (name == "study") out += v.study;
    else if (name == "out") out += v.out;
    else if (name == "python") out += v.python;
    else if (name == "ricochet") out += v.ricochet;
    else if (name.rfind("sweep:", 0) == 0) {
      const auto it = v.sweeps.find(name.substr(6));
      if (it == v.sweeps.end())
        throw InputError("{" + name + "}: no sweep \"" + name.substr(6) + "\" in the step's tiers; its sweeps: " +
                         (sweeps.empty() ? "none" : sweeps));
      out += it->second;
    } else {
      throw InputError("unknown placeholder {" + name + "}; allowed: {study}, {out}, {sweep:NAME}, {python}, {ricochet} "
                       "(and {{ for a literal {)");
    }
    i = close;
  }
  return out;
}

std::string report_python() {
  const char* python = std::getenv("RICOCHET_PYTHON");
  return python && *python ? python : "/usr/bin/python3";
}

std::filesystem::path this_program() {
  std::error_code ec;
  const std::filesystem::path p = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path("ricochet") : p;
}

}  // namespace ricochet
