// The placeholders of a study's `[[post]]` steps (docs/studies.md): {study} the study folder,
// {out} the study's output folder, {sweep:NAME} the output folder of its sweep NAME, {python}
// the reports' interpreter, {ricochet} the program; `{{` is a literal `{`.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace ricochet {

// The values placeholders expand to.
struct Placeholders {
  std::string study, out, python, ricochet;
  std::map<std::string, std::string> sweeps;  // NAME -> its output folder
};

// `text` with every placeholder replaced. Throws InputError "unknown placeholder {X}; allowed:
// ..." (without a location: the caller adds it) for a placeholder that is not one of the above,
// a {sweep:NAME} whose NAME is not in `values.sweeps`, or a `{` without its `}`.
std::string expand_placeholders(const std::string& text, const Placeholders& values);

// The interpreter of the report scripts: $RICOCHET_PYTHON if set, else /usr/bin/python3.
std::string report_python();

// This program's path (/proc/self/exe).
std::filesystem::path this_program();

}  // namespace ricochet
