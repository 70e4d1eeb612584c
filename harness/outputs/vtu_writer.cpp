#include "harness/outputs/vtu_writer.hpp"

#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <set>
#include <stdexcept>
#include <string_view>
#include <type_traits>

#include <zlib.h>

#include "harness/outputs/csv_writer.hpp"

// Non-finite values. VTK's XML reader (vtkXMLDataParser::ParseAsciiData, in the VTK sources
// checked) reads format="ascii" arrays with `std::istream >> value` and stops at the first token
// that fails. libstdc++'s extraction rejects every spelling of NaN and infinity (checked: "nan",
// "NaN", "inf", "-inf", "Infinity"), so no ASCII token reads back as non-finite in VTK: the
// array comes up short and ParaView reports an error for the file (the known problem behind
// ParaView issue #19042, where VTK's own ASCII output with NaN cannot be read back). meshio
// reads ascii arrays with numpy.fromstring, which accepts "nan", "inf" and "-inf". So
// non-finite values are written as those three tokens, unchanged; a field meant for ParaView
// must be finite, or be written in the binary or base64 encodings, which carry any bits.

namespace ricochet {
namespace {

static_assert(sizeof(int) == 4, "Int32 arrays are written from int");
constexpr std::uint8_t vtk_triangle = 5;
constexpr std::uint8_t vtk_quad = 9;
constexpr std::uint8_t vtk_tetra = 10;
constexpr std::uint8_t vtk_hexahedron = 12;

[[noreturn]] void invalid(const std::string& what) {
  throw std::invalid_argument("format_vtu: " + what);
}

// Rejects names XML 1.0 cannot hold in an attribute (control characters) and empty ones.
void check_text(std::string_view text, const std::string& what) {
  if (text.empty()) invalid(what + " is empty");
  for (const char c : text) {
    if (static_cast<unsigned char>(c) < 0x20) invalid(what + " contains a control character");
  }
}

// `text` as the inside of a double-quoted XML attribute value.
std::string xml_attribute(std::string_view text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

void append_int(std::string& out, std::int64_t value) {
  char buffer[24];
  out.append(buffer, std::to_chars(buffer, buffer + sizeof buffer, value).ptr);
}

// Base64 (RFC 4648, with '=' padding) of `n` bytes, appended to `out`.
void append_base64(std::string& out, const unsigned char* p, std::size_t n) {
  static constexpr char digits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  for (std::size_t i = 0; i < n; i += 3) {
    const unsigned b0 = p[i], b1 = i + 1 < n ? p[i + 1] : 0u, b2 = i + 2 < n ? p[i + 2] : 0u;
    out += digits[b0 >> 2];
    out += digits[((b0 & 3u) << 4) | (b1 >> 4)];
    out += i + 1 < n ? digits[((b1 & 15u) << 2) | (b2 >> 6)] : '=';
    out += i + 2 < n ? digits[b2 & 63u] : '=';
  }
}

void append_u64(std::string& bytes, std::uint64_t v) {
  char b[sizeof v];
  std::memcpy(b, &v, sizeof v);
  bytes.append(b, sizeof v);
}

// The DataArrays of one document in the chosen encoding. ascii arrays are written as text in
// place; binary arrays go to `appended` and are written at the end; base64 ones inline.
class ArrayWriter {
 public:
  explicit ArrayWriter(const VtuFormat& f) : f_(f) {}

  // One DataArray: `values` (count values, components per tuple), with `text` writing its
  // ascii body; tensors get ComponentName0..5.
  template <class T, class Text>
  void add(std::string& out, const char* type, std::string_view name, int components, const T* values,
           std::size_t count, Text&& text, bool tensor = false) {
    constexpr const char* in = "        ";  // DataArray indentation inside Piece sections
    out += in;
    out += "<DataArray type=\"";
    out += type;
    out += '"';
    if (!name.empty()) out += " Name=\"" + xml_attribute(name) + '"';
    if (components > 1) out += " NumberOfComponents=\"" + std::to_string(components) + '"';
    if (tensor) {
      static constexpr const char* names[] = {"XX", "YY", "ZZ", "XY", "YZ", "XZ"};
      for (int k = 0; k < 6; ++k) out += " ComponentName" + std::to_string(k) + "=\"" + names[k] + '"';
    }
    const auto* bytes = reinterpret_cast<const unsigned char*>(values);
    const std::size_t size = count * sizeof(T);
    switch (f_.encoding) {
      case VtuEncoding::ascii:
        out += " format=\"ascii\">\n";
        text(out);
        out += in;
        out += "</DataArray>\n";
        return;
      case VtuEncoding::binary:
        out += " format=\"appended\" offset=\"" + std::to_string(appended_.size()) + "\"/>\n";
        block(appended_, bytes, size);
        return;
      case VtuEncoding::base64: {
        out += " format=\"binary\">\n";
        out += in;
        out += "  ";
        std::string raw;
        const std::size_t head = block(raw, bytes, size);
        if (f_.compression == VtuCompression::none) {
          append_base64(out, reinterpret_cast<const unsigned char*>(raw.data()), raw.size());
        } else {
          append_base64(out, reinterpret_cast<const unsigned char*>(raw.data()), head);
          append_base64(out, reinterpret_cast<const unsigned char*>(raw.data()) + head, raw.size() - head);
        }
        out += '\n';
        out += in;
        out += "</DataArray>\n";
        return;
      }
    }
  }

  // The <AppendedData> section (binary encoding), or nothing.
  void finish(std::string& out) const {
    if (f_.encoding != VtuEncoding::binary) return;
    out += "  <AppendedData encoding=\"raw\">\n   _";
    out += appended_;
    out += "\n  </AppendedData>\n";
  }

 private:
  // Appends one array's header and data to `bytes`; returns the header's size in bytes.
  std::size_t block(std::string& bytes, const unsigned char* data, std::size_t size) const {
    if (f_.compression == VtuCompression::none) {
      append_u64(bytes, size);
      bytes.append(reinterpret_cast<const char*>(data), size);
      return sizeof(std::uint64_t);
    }
    const std::size_t blocks = (size + kVtuZlibBlock - 1) / kVtuZlibBlock;
    const std::size_t at = bytes.size();
    append_u64(bytes, blocks);
    append_u64(bytes, kVtuZlibBlock);
    append_u64(bytes, size % kVtuZlibBlock);
    for (std::size_t b = 0; b < blocks; ++b) append_u64(bytes, 0);  // sizes, filled in below
    const std::size_t head = bytes.size() - at;
    std::string packed(compressBound(kVtuZlibBlock), '\0');
    for (std::size_t b = 0; b < blocks; ++b) {
      const std::size_t len = std::min(kVtuZlibBlock, size - b * kVtuZlibBlock);
      uLongf packed_size = static_cast<uLongf>(packed.size());
      if (compress2(reinterpret_cast<Bytef*>(packed.data()), &packed_size, data + b * kVtuZlibBlock,
                    static_cast<uLong>(len), Z_BEST_SPEED) != Z_OK)
        throw std::runtime_error("format_vtu: zlib compress2 failed");
      bytes.append(packed.data(), packed_size);
      const std::uint64_t word = packed_size;
      std::memcpy(bytes.data() + at + 8 * (3 + b), &word, sizeof word);
    }
    return head;
  }

  VtuFormat f_;
  std::string appended_;
};

// `components` values per line.
template <typename T>
void append_values(std::string& out, const std::vector<T>& values, std::size_t components = 1) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    if constexpr (std::is_same_v<T, double>) {
      append_number(out, values[i]);
    } else {
      append_int(out, values[i]);
    }
    out += (i + 1) % components == 0 ? '\n' : ' ';
  }
}

// Points and point vectors as 3 n values x y z: a 2 x n matrix with z = 0, a 3 x n one as it is.
std::vector<double> xyz(const Eigen::Matrix2Xd& m) {
  std::vector<double> v(3 * static_cast<std::size_t>(m.cols()), 0.0);
  for (Eigen::Index j = 0; j < m.cols(); ++j) {
    v[3 * j] = m(0, j);
    v[3 * j + 1] = m(1, j);
  }
  return v;
}
std::vector<double> xyz(const Eigen::Matrix3Xd& m) { return {m.data(), m.data() + m.size()}; }

// The cells of one VTK type, in the order they are written.
struct CellBlock {
  std::vector<std::int32_t> nodes;  // `count` cells of `corners` point indices each
  std::size_t count;
  int corners;
  std::uint8_t vtk_type;
  const char* kind;  // the cell's name in messages
};

template <std::size_t N>
CellBlock block_of(const std::vector<std::array<int, N>>& cells, std::uint8_t type, const char* kind) {
  CellBlock b{{}, cells.size(), static_cast<int>(N), type, kind};
  b.nodes.reserve(N * cells.size());
  for (const auto& c : cells) b.nodes.insert(b.nodes.end(), c.begin(), c.end());
  return b;
}

std::vector<CellBlock> cell_blocks(const VtuData& d) {
  return {block_of(d.quads, vtk_quad, "quad"), block_of(d.tris, vtk_triangle, "triangle")};
}
std::vector<CellBlock> cell_blocks(const VtuData3& d) {
  return {block_of(d.hexes, vtk_hexahedron, "hexahedron"), block_of(d.tets, vtk_tetra, "tetrahedron")};
}

// Checks the names (non-empty, no control characters, not already in `seen`, the names used so
// far in `section`) and that every array has `expected` entries as counted by `size`.
template <typename Fields, typename Size>
void check_fields(const Fields& fields, const char* section, std::size_t expected, Size size,
                  std::set<std::string_view>& seen) {
  for (const auto& [name, values] : fields) {
    check_text(name, std::string(section) + " array name");
    if (!seen.insert(name).second) invalid(std::string(section) + " array '" + name + "' repeated");
    const auto got = static_cast<std::size_t>(size(values));
    if (got != expected) {
      invalid(std::string(section) + " array '" + name + "' has " + std::to_string(got) +
              " entries, expected " + std::to_string(expected));
    }
  }
}

void check_cells(const CellBlock& b, Eigen::Index n) {
  for (std::size_t c = 0; c < b.count; ++c) {
    for (int k = 0; k < b.corners; ++k) {
      const int p = b.nodes[c * static_cast<std::size_t>(b.corners) + static_cast<std::size_t>(k)];
      if (p < 0 || p >= n) {
        invalid(std::string(b.kind) + ' ' + std::to_string(c) + " refers to point " +
                std::to_string(p) + " but there are " + std::to_string(n) + " points");
      }
    }
  }
}

// The document of format_vtu for a VtuData or a VtuData3.
template <class Data>
std::string format_piece(const Data& data, const VtuFormat& format) {
  const Eigen::Index n = data.points.cols();
  const std::vector<CellBlock> blocks = cell_blocks(data);
  std::size_t cells = 0, corners = 0;
  for (const CellBlock& b : blocks) {
    cells += b.count;
    corners += b.count * static_cast<std::size_t>(b.corners);
  }
  if (!std::isfinite(data.time)) invalid("time is not finite");
  if (format.encoding == VtuEncoding::ascii && format.compression != VtuCompression::none)
    invalid("compression needs the binary or base64 encoding");
  for (const CellBlock& b : blocks) check_cells(b, n);
  const auto points = static_cast<std::size_t>(n);
  const auto columns = [](const auto& m) { return m.cols(); };
  const auto entries = [](const auto& v) { return v.size(); };
  std::set<std::string_view> point_names, cell_names;
  check_fields(data.point_vectors, "PointData", points, columns, point_names);
  check_fields(data.point_scalars, "PointData", points, entries, point_names);
  check_fields(data.point_ints, "PointData", points, entries, point_names);
  check_fields(data.cell_scalars, "CellData", cells, entries, cell_names);
  check_fields(data.cell_tensors, "CellData", 6 * cells, entries, cell_names);
  check_fields(data.cell_ints, "CellData", cells, entries, cell_names);

  const bool ascii = format.encoding == VtuEncoding::ascii;
  std::string out = "<?xml version=\"1.0\"?>\n";
  if (ascii) {
    out += "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n";
  } else {
    out += "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"";
    out += std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian";
    out += "\" header_type=\"UInt64\"";
    if (format.compression == VtuCompression::zlib) out += " compressor=\"vtkZLibDataCompressor\"";
    out += ">\n";
  }
  out +=
      "  <UnstructuredGrid>\n"
      "    <FieldData>\n"
      "      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" "
      "format=\"ascii\">\n";
  append_number(out, data.time);
  out += "\n      </DataArray>\n    </FieldData>\n";
  out += "    <Piece NumberOfPoints=\"" + std::to_string(n) + "\" NumberOfCells=\"" +
         std::to_string(cells) + "\">\n";

  ArrayWriter arrays(format);
  const auto doubles = [&](const char* name, int components, const std::vector<double>& v) {
    arrays.add(out, "Float64", name, components, v.data(), v.size(),
               [&](std::string& o) { append_values(o, v, static_cast<std::size_t>(components)); }, components == 6);
  };
  const auto ints = [&](const char* type, const char* name, const auto& v) {
    arrays.add(out, type, name, 1, v.data(), v.size(), [&](std::string& o) { append_values(o, v); });
  };
  out += "      <PointData>\n";
  for (const auto& [name, values] : data.point_vectors) doubles(name.c_str(), 3, xyz(values));
  for (const auto& [name, values] : data.point_scalars) doubles(name.c_str(), 1, values);
  for (const auto& [name, values] : data.point_ints) ints("Int32", name.c_str(), values);
  out += "      </PointData>\n      <CellData>\n";
  for (const auto& [name, values] : data.cell_scalars) doubles(name.c_str(), 1, values);
  for (const auto& [name, values] : data.cell_tensors) doubles(name.c_str(), 6, values);
  for (const auto& [name, values] : data.cell_ints) ints("Int32", name.c_str(), values);
  out += "      </CellData>\n      <Points>\n";
  doubles("Points", 3, xyz(data.points));
  out += "      </Points>\n      <Cells>\n";

  // Connectivity (ascii: one cell per line), the end of each cell, its VTK type.
  std::vector<std::int32_t> connectivity;
  std::vector<std::int64_t> offsets;
  std::vector<std::uint8_t> types;
  connectivity.reserve(corners);
  offsets.reserve(cells);
  types.reserve(cells);
  for (const CellBlock& b : blocks) {
    connectivity.insert(connectivity.end(), b.nodes.begin(), b.nodes.end());
    for (std::size_t c = 0; c < b.count; ++c) {
      offsets.push_back((offsets.empty() ? 0 : offsets.back()) + b.corners);
      types.push_back(b.vtk_type);
    }
  }
  arrays.add(out, "Int32", "connectivity", 1, connectivity.data(), connectivity.size(), [&](std::string& o) {
    std::size_t at = 0;
    for (const CellBlock& b : blocks)
      for (std::size_t c = 0; c < b.count; ++c)
        for (int k = 0; k < b.corners; ++k) {
          append_int(o, connectivity[at++]);
          o += k + 1 < b.corners ? ' ' : '\n';
        }
  });
  ints("Int64", "offsets", offsets);
  ints("UInt8", "types", types);
  out += "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n";
  arrays.finish(out);
  out += "</VTKFile>\n";
  return out;
}

}  // namespace

std::string format_vtu(const VtuData& data, const VtuFormat& format) { return format_piece(data, format); }

std::string format_vtu(const VtuData3& data, const VtuFormat& format) { return format_piece(data, format); }

std::string format_pvd(const std::vector<std::pair<double, std::string>>& time_and_relative_file) {
  std::string out =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      "  <Collection>\n";
  for (const auto& [time, file] : time_and_relative_file) {
    if (!std::isfinite(time)) throw std::invalid_argument("format_pvd: time is not finite");
    if (file.empty()) throw std::invalid_argument("format_pvd: empty file name");
    for (const char c : file) {
      if (static_cast<unsigned char>(c) < 0x20) {
        throw std::invalid_argument("format_pvd: file name contains a control character");
      }
    }
    // 15 significant digits: a step's time n dt prints as the user wrote it (300 x 1e-5 is
    // 0.0030000000000000005 in full), and distinct steps still print distinct. The VTU file
    // itself keeps the exact time (TimeValue).
    char label[32];
    std::snprintf(label, sizeof label, "%.15g", time);
    out += "    <DataSet timestep=\"";
    out += label;
    out += "\" group=\"\" part=\"0\" file=\"" + xml_attribute(file) + "\"/>\n";
  }
  out += "  </Collection>\n</VTKFile>\n";
  return out;
}

}  // namespace ricochet
