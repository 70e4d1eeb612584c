// What a sweep run's result is computed from beyond its base case's text and its overrides
// (harness/sweeps/sweep_plan.hpp, SweepPlan::request): the mesh files its case reads and the
// build of the program that runs it. Both go into the run's overrides.json, so that resume
// reruns a run whose mesh file was edited, or that a different build of the program ran.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "harness/input/case_spec.hpp"

namespace ricochet {

// The build identity of `program` (empty: this process's own executable):
// "gnu-build-id:<hex>", the ELF note .note.gnu.build-id that the linker writes (read from the
// loaded image with dl_iterate_phdr when `program` is this process's executable, else from the
// file's PT_NOTE segments: the same text either way, so a sweep run in-process by a test and a
// merge by the program agree), else "fnv1a:<16 hex digits>", the FNV-1a hash of the file's bytes
// (a wrapper script, or an executable linked without a build id); "none" if it cannot be read.
// Computed once per path per process. A rebuild that links the same binary keeps the same
// identity.
std::string program_build_id(const std::filesystem::path& program = {});

// The .note.gnu.build-id of this process's executable as hex digits; empty if it has none.
std::string own_gnu_build_id();

// The mesh files the case reads: every `[meshes.NAME] file`, used by a body or not (reading the
// case reads them all), as resolved against the case file's folder.
std::vector<std::filesystem::path> mesh_files(const CaseSpec& c);

// The FNV-1a hash of a file's bytes (16 hex digits); empty if it cannot be read.
std::string file_fnv1a(const std::filesystem::path& path);

}  // namespace ricochet
