#include "harness/outputs/vtu_writer.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <set>
#include <stdexcept>
#include <string_view>
#include <type_traits>

#include "harness/outputs/csv_writer.hpp"

// Non-finite values. VTK's XML reader (vtkXMLDataParser::ParseAsciiData, in the VTK sources
// checked) reads format="ascii" arrays with `std::istream >> value` and stops at the first token
// that fails. libstdc++'s extraction rejects every spelling of NaN and infinity (checked: "nan",
// "NaN", "inf", "-inf", "Infinity"), so no ASCII token reads back as non-finite in VTK: the
// array comes up short and ParaView reports an error for the file (the known problem behind
// ParaView issue #19042, where VTK's own ASCII output with NaN cannot be read back). meshio
// reads ascii arrays with numpy.fromstring, which accepts "nan", "inf" and "-inf". So
// non-finite values are written as those three tokens, unchanged; a field meant for ParaView
// must be finite, or this writer must switch to base64 "binary" arrays, which carry any bits.

namespace ricochet {
namespace {

constexpr std::uint8_t vtk_triangle = 5;
constexpr std::uint8_t vtk_quad = 9;

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

void open_array(std::string& out, const char* indent, const char* type, std::string_view name,
                int components) {
  out += indent;
  out += "<DataArray type=\"";
  out += type;
  out += '"';
  if (!name.empty()) out += " Name=\"" + xml_attribute(name) + '"';
  if (components > 1) out += " NumberOfComponents=\"" + std::to_string(components) + '"';
  out += " format=\"ascii\">\n";
}

void close_array(std::string& out, const char* indent) {
  out += indent;
  out += "</DataArray>\n";
}

// A 2 x n matrix as 3-component tuples (x y 0), one per line.
void append_xy0(std::string& out, const Eigen::Matrix2Xd& m) {
  for (Eigen::Index j = 0; j < m.cols(); ++j) {
    append_number(out, m(0, j));
    out += ' ';
    append_number(out, m(1, j));
    out += " 0\n";
  }
}

// Point indices of each cell, one cell per line.
template <std::size_t N>
void append_cells(std::string& out, const std::vector<std::array<int, N>>& cells) {
  for (const auto& cell : cells) {
    for (std::size_t k = 0; k < N; ++k) {
      if (k > 0) out += ' ';
      append_int(out, cell[k]);
    }
    out += '\n';
  }
}

// One value per line.
template <typename T>
void append_values(std::string& out, const std::vector<T>& values) {
  for (const T value : values) {
    if constexpr (std::is_same_v<T, double>) {
      append_number(out, value);
    } else {
      append_int(out, value);
    }
    out += '\n';
  }
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

template <std::size_t N>
void check_cells(const std::vector<std::array<int, N>>& cells, const char* kind, Eigen::Index n) {
  for (std::size_t c = 0; c < cells.size(); ++c) {
    for (const int p : cells[c]) {
      if (p < 0 || p >= n) {
        invalid(std::string(kind) + ' ' + std::to_string(c) + " refers to point " +
                std::to_string(p) + " but there are " + std::to_string(n) + " points");
      }
    }
  }
}

}  // namespace

std::string format_vtu(const VtuData& data) {
  const Eigen::Index n = data.points.cols();
  const std::size_t cells = data.quads.size() + data.tris.size();
  if (!std::isfinite(data.time)) invalid("time is not finite");
  check_cells(data.quads, "quad", n);
  check_cells(data.tris, "triangle", n);
  const auto points = static_cast<std::size_t>(n);
  const auto columns = [](const Eigen::Matrix2Xd& m) { return m.cols(); };
  const auto entries = [](const auto& v) { return v.size(); };
  std::set<std::string_view> point_names, cell_names;
  check_fields(data.point_vectors, "PointData", points, columns, point_names);
  check_fields(data.point_scalars, "PointData", points, entries, point_names);
  check_fields(data.cell_scalars, "CellData", cells, entries, cell_names);
  check_fields(data.cell_ints, "CellData", cells, entries, cell_names);

  std::string out =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      "  <UnstructuredGrid>\n"
      "    <FieldData>\n"
      "      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" "
      "format=\"ascii\">\n";
  append_number(out, data.time);
  out += "\n      </DataArray>\n    </FieldData>\n";
  out += "    <Piece NumberOfPoints=\"" + std::to_string(n) + "\" NumberOfCells=\"" +
         std::to_string(cells) + "\">\n";

  constexpr const char* in = "        ";  // DataArray indentation inside Piece sections
  out += "      <PointData>\n";
  for (const auto& [name, values] : data.point_vectors) {
    open_array(out, in, "Float64", name, 3);
    append_xy0(out, values);
    close_array(out, in);
  }
  for (const auto& [name, values] : data.point_scalars) {
    open_array(out, in, "Float64", name, 1);
    append_values(out, values);
    close_array(out, in);
  }
  out += "      </PointData>\n      <CellData>\n";
  for (const auto& [name, values] : data.cell_scalars) {
    open_array(out, in, "Float64", name, 1);
    append_values(out, values);
    close_array(out, in);
  }
  for (const auto& [name, values] : data.cell_ints) {
    open_array(out, in, "Int32", name, 1);
    append_values(out, values);
    close_array(out, in);
  }
  out += "      </CellData>\n      <Points>\n";
  open_array(out, in, "Float64", "Points", 3);
  append_xy0(out, data.points);
  close_array(out, in);
  out += "      </Points>\n      <Cells>\n";

  open_array(out, in, "Int32", "connectivity", 1);
  append_cells(out, data.quads);
  append_cells(out, data.tris);
  close_array(out, in);
  open_array(out, in, "Int64", "offsets", 1);
  std::int64_t offset = 0;
  for (std::size_t c = 0; c < cells; ++c) {
    offset += c < data.quads.size() ? 4 : 3;
    append_int(out, offset);
    out += '\n';
  }
  close_array(out, in);
  open_array(out, in, "UInt8", "types", 1);
  for (std::size_t c = 0; c < cells; ++c) {
    append_int(out, c < data.quads.size() ? vtk_quad : vtk_triangle);
    out += '\n';
  }
  close_array(out, in);
  out += "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
  return out;
}

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
