#include "harness/sweeps/run_identity.hpp"

#include <elf.h>
#include <link.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <mutex>
#include <system_error>
#include <variant>
#include <vector>


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

// The GNU build id among the notes of one PT_NOTE segment, [p, end); empty if none.
std::string build_id_note(const unsigned char* p, const unsigned char* end) {
  while (end - p >= static_cast<std::ptrdiff_t>(sizeof(ElfW(Nhdr)))) {
    ElfW(Nhdr) nh;
    std::memcpy(&nh, p, sizeof nh);
    const unsigned char* name = p + sizeof nh;
    if (static_cast<std::size_t>(end - name) < align4(nh.n_namesz)) break;
    const unsigned char* desc = name + align4(nh.n_namesz);
    if (static_cast<std::size_t>(end - desc) < nh.n_descsz) break;
    if (nh.n_type == NT_GNU_BUILD_ID && nh.n_namesz == 4 && std::memcmp(name, "GNU", 4) == 0) return hex(desc, nh.n_descsz);
    if (static_cast<std::size_t>(end - desc) < align4(nh.n_descsz)) break;
    p = desc + align4(nh.n_descsz);
  }
  return {};
}

// The build id in the PT_NOTE segments of the first object dl_iterate_phdr reports: the main
// program, as loaded.
int find_build_id(dl_phdr_info* info, std::size_t, void* data) {
  auto& out = *static_cast<std::string*>(data);
  for (int i = 0; i < info->dlpi_phnum && out.empty(); ++i) {
    const ElfW(Phdr)& ph = info->dlpi_phdr[i];
    if (ph.p_type != PT_NOTE) continue;
    const auto* p = reinterpret_cast<const unsigned char*>(info->dlpi_addr + ph.p_vaddr);
    out = build_id_note(p, p + ph.p_memsz);
  }
  return 1;  // only the first object, the program itself
}

// The build id of an ELF file of this machine's class, read from its PT_NOTE segments; empty
// for another file (a script) or one without a build id. The same as find_build_id gives for
// the program when it runs.
std::string file_build_id(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  ElfW(Ehdr) eh;
  if (!in.read(reinterpret_cast<char*>(&eh), sizeof eh) || std::memcmp(eh.e_ident, ELFMAG, SELFMAG) != 0 ||
      eh.e_ident[EI_CLASS] != (sizeof(void*) == 8 ? ELFCLASS64 : ELFCLASS32) || eh.e_phentsize != sizeof(ElfW(Phdr)))
    return {};
  for (int i = 0; i < eh.e_phnum; ++i) {
    ElfW(Phdr) ph;
    in.seekg(static_cast<std::streamoff>(eh.e_phoff + i * sizeof ph));
    if (!in.read(reinterpret_cast<char*>(&ph), sizeof ph)) return {};
    if (ph.p_type != PT_NOTE || ph.p_filesz > (1u << 20)) continue;
    std::vector<unsigned char> seg(ph.p_filesz);
    const auto here = in.tellg();
    in.seekg(static_cast<std::streamoff>(ph.p_offset));
    if (!in.read(reinterpret_cast<char*>(seg.data()), static_cast<std::streamsize>(seg.size()))) return {};
    in.seekg(here);
    if (std::string id = build_id_note(seg.data(), seg.data() + seg.size()); !id.empty()) return id;
  }
  return {};
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
  const std::string gnu = path == self ? own_gnu_build_id() : file_build_id(path);
  std::string id;
  if (!gnu.empty()) id = "gnu-build-id:" + gnu;
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
