// Whole-file output that readers (a plotting script, a sweep driver polling a directory)
// never see half-written.
#pragma once

#include <filesystem>
#include <string_view>

namespace ricochet {

// Writes `content` (bytes, unchanged) to `path`: creates missing parent directories, writes
// `path` + ".tmp" in the same directory, flushes and closes it checking every step, then renames
// it over `path` (atomic on POSIX file systems: a reader sees the old file or the new one). An
// existing `path` is replaced. The temporary name is fixed, so at most one writer per `path`.
// The data is not fsync'ed: the file survives a crash of the process, not a power loss.
// On failure the temporary is removed, `path` is left as it was, and std::runtime_error is
// thrown with a one-line message naming the path and the OS error, e.g.
//   cannot write 'out/summary.json': cannot create directory 'out': Not a directory
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

}  // namespace ricochet
