#include "harness/outputs/atomic_file.hpp"

#include <cerrno>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <system_error>

namespace ricochet {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void fail(const fs::path& path, const std::string& detail) {
  throw std::runtime_error("cannot write '" + path.string() + "': " + detail);
}

// The strerror text of errno (EIO if a failing call left errno unset), without strerror's
// shared buffer.
std::string last_os_error() { return std::generic_category().message(errno != 0 ? errno : EIO); }

}  // namespace

void write_file_atomic(const fs::path& path, std::string_view content) {
  if (path.filename().empty()) fail(path, "the path names no file");

  const fs::path parent = path.parent_path();
  if (!parent.empty()) {
    std::error_code ec;
    fs::create_directories(parent, ec);
    if (ec) fail(path, "cannot create directory '" + parent.string() + "': " + ec.message());
  }

  fs::path temporary = path;
  temporary += ".tmp";
  errno = 0;
  std::FILE* file = std::fopen(temporary.c_str(), "wb");
  if (file == nullptr) {
    fail(path, "cannot create '" + temporary.string() + "': " + last_os_error());
  }

  // Any failure from here on removes the temporary before throwing.
  const auto discard = [&](const std::string& detail) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    fail(path, detail);
  };
  if (std::fwrite(content.data(), 1, content.size(), file) != content.size() ||
      std::fflush(file) != 0) {
    const std::string detail = last_os_error();
    std::fclose(file);
    discard(detail);
  }
  if (std::fclose(file) != 0) discard(last_os_error());

  std::error_code ec;
  fs::rename(temporary, path, ec);
  if (ec) discard("cannot rename '" + temporary.string() + "' over it: " + ec.message());
}

}  // namespace ricochet
