#include "harness/sweeps/run_identity.hpp"

#include <elf.h>
#include <link.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <map>
#include <mutex>
#include <system_error>
#include <variant>


namespace ricochet {
namespace {

namespace fs = std::filesystem;

std::string hex(const unsigned char* bytes, std::size_t n) {
  static const char* digits = "0123456789abcdef";
  std::string s;
  for (std::size_t i = 0; i < n; ++i) {
    s += digits[bytes[i] >> 4];
    s += digits[bytes[i] & 15];
  }
  return s;
}

std::size_t align4(std::size_t n) { return (n + 3) & ~std::size_t{3}; }

// The build id in the PT_NOTE segments of the first object dl_iterate_phdr reports: the main
// program.
int find_build_id(dl_phdr_info* info, std::size_t, void* data) {
  auto& out = *static_cast<std::string*>(data);
  for (int i = 0; i < info->dlpi_phnum; ++i) {
    const ElfW(Phdr)& ph = info->dlpi_phdr[i];
    if (ph.p_type != PT_NOTE) continue;
    const auto* p = reinterpret_cast<const unsigned char*>(info->dlpi_addr + ph.p_vaddr);
    const unsigned char* end = p + ph.p_memsz;
    while (p + sizeof(ElfW(Nhdr)) <= end) {
      const auto* nh = reinterpret_cast<const ElfW(Nhdr)*>(p);
      const unsigned char* name = p + sizeof(ElfW(Nhdr));
      const unsigned char* desc = name + align4(nh->n_namesz);
      if (desc + nh->n_descsz > end) break;
      if (nh->n_type == NT_GNU_BUILD_ID && nh->n_namesz == 4 && std::string_view(reinterpret_cast<const char*>(name), 3) == "GNU") {
        out = hex(desc, nh->n_descsz);
        return 1;
      }
      p = desc + align4(nh->n_descsz);
    }
  }
  return 1;  // only the first object, the program itself
}

fs::path own_executable() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : p;
}

}  // namespace

std::string own_gnu_build_id() {
  static const std::string id = [] {
    std::string s;
    dl_iterate_phdr(find_build_id, &s);
    return s;
  }();
  return id;
}

std::string program_build_id(const fs::path& program) {
  static std::mutex mutex;
  static std::map<fs::path, std::string> known;
  const std::lock_guard<std::mutex> lock(mutex);
  std::error_code ec;
  const fs::path self = own_executable();
  fs::path path = program.empty() ? self : fs::weakly_canonical(program, ec);
  if (ec) path = program;
  if (const auto it = known.find(path); it != known.end()) return it->second;
  std::string id;
  if (path == self && !own_gnu_build_id().empty()) id = "gnu-build-id:" + own_gnu_build_id();
  else if (const std::string h = file_fnv1a(path); !h.empty()) id = "fnv1a:" + h;
  else id = "none";
  known.emplace(path, id);
  return id;
}

std::vector<fs::path> mesh_files(const CaseSpec& c) {
  std::vector<fs::path> out;
  for (const auto& [name, m] : c.meshes)
    if (const auto* g = std::get_if<GmshFile>(&m.source)) out.push_back(g->path);
  return out;
}

std::string file_fnv1a(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return {};
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  std::uint64_t h = 1469598103934665603ull;
  char buf[1 << 16];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    for (std::streamsize i = 0; i < in.gcount(); ++i) {
      h ^= static_cast<unsigned char>(buf[i]);
      h *= 1099511628211ull;
    }
    if (!in) break;
  }
  char text[20];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(h));
  return text;
}

}  // namespace ricochet
