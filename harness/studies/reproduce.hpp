// `ricochet reproduce [STUDY...] [--tier fast|full] [--out DIR] [--studies DIR] [--force]
// [--quiet] [--no-report]` (docs/studies.md): runs the chosen studies of a tier (every study of
// --studies DIR when none is named), each into DIR/<study>/ (study_run.hpp), then draws the
// report of each study whose inputs changed (report_stamp.hpp) and the index.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

namespace ricochet {

struct ReproduceCommand {
  std::vector<std::string> studies;  // STUDY arguments; empty: every study of studies_dir
  std::string tier = "full";         // "fast" or "full"
  std::string out_dir;               // empty: results/<tier>
  std::string studies_dir;           // empty: default_studies_dir() (study_spec.hpp)
  bool force = false;                // rerun every run, redraw every report
  bool quiet = false;                // no run progress, no per-gate lines
  bool no_report = false;            // draw no report
};

inline constexpr int kExitReproduceGates = 4;

// Reads and checks every chosen study first (study.toml, its tier's sweep and gate files, their
// cases): bad input throws InputError and nothing is written. Then runs the studies one after
// the other; one that fails does not stop the others. Returns 0 every study passed (and every
// report was drawn), 4 a gate failed and nothing failed, 1 a study (a sweep, a run or a post
// step) or a report failed.
int run_command(const ReproduceCommand& c, std::ostream& out, std::ostream& err);

}  // namespace ricochet
