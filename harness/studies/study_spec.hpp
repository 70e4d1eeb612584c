// A study (docs/studies.md): a folder holding a study.toml that names the study's sweeps, their
// gates and tiers, its post-processing steps and its report layout. This reads and validates
// study.toml and finds the studies of a folder; harness/studies/reproduce.hpp runs them.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace ricochet {

inline const std::vector<std::string> kStudyTiers = {"fast", "full"};

// One `[[sweep]]` entry.
struct StudySweep {
  std::string name;                  // unique per tier; the folder <out>/<study>/<name>
  std::filesystem::path file;        // the sweep file, absolute
  std::vector<std::string> tiers;    // of kStudyTiers, in that order
  std::filesystem::path gates;       // absolute; empty: no gates
  int repeat = 1, jobs = 1, threads = 1;
  std::string where;                 // "FILE:LINE: sweep[N]", for messages

  bool in(const std::string& tier) const;
};

// One `[[post]]` entry: a command run after the tier's sweeps.
struct StudyPost {
  std::string name;                  // unique
  std::vector<std::string> command;  // argv, placeholders unexpanded (study_placeholders.hpp)
  std::vector<std::string> tiers;
  std::string table;                 // a CSV it writes, placeholders unexpanded; empty: none
  std::filesystem::path gates;       // absolute; set exactly when `table` is
  std::string where;

  bool in(const std::string& tier) const;
};

struct StudySpec {
  std::string name;                  // the folder's name
  std::filesystem::path folder;      // absolute
  std::filesystem::path file;        // folder/study.toml
  std::string title, summary;
  std::optional<long> order;
  std::vector<StudySweep> sweeps;
  std::vector<StudyPost> posts;
  std::filesystem::path plugin;      // [report] plugin, absolute; empty: none
  // [requires]: what the study needs besides ricochet (external codes, docs/peers.md); a study
  // whose requirement is missing is skipped, never passed.
  std::vector<std::string> required_programs;        // found on PATH
  std::vector<std::string> required_python_modules;  // importable by the reports' Python

  // The sweep entries and post steps of a tier, in file order.
  std::vector<const StudySweep*> sweeps_of(const std::string& tier) const;
  std::vector<const StudyPost*> posts_of(const std::string& tier) const;
};

// Reads and validates FOLDER/study.toml. Throws InputError, one line "FILE:LINE: KEY: what is
// wrong; allowed: ...", for a TOML syntax error, an unknown or missing key, a wrong type or
// value, a file that does not exist, a duplicate name, or a placeholder that names no sweep of
// the step's tiers. The sweep and gate files themselves are read by the caller.
StudySpec read_study(const std::filesystem::path& folder);

// The studies below `dir`: every folder one level down that holds a study.toml, read, in the
// order of `order` (studies without one last), then the folder name. Throws InputError if `dir`
// is not a folder, or for a bad study.toml.
std::vector<StudySpec> discover_studies(const std::filesystem::path& dir);

// A STUDY argument: the name of a folder in `dir` holding a study.toml, or a path to a folder
// holding one. Throws InputError naming the argument and the studies of `dir`.
StudySpec find_study(const std::string& arg, const std::filesystem::path& dir);

// The default of --studies: $RICOCHET_CASES if set and not empty, else the source tree's cases/.
std::filesystem::path default_studies_dir();

}  // namespace ricochet
