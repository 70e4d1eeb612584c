#include "harness/input/gmsh_reader.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <set>
#include <span>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "harness/input/input_error.hpp"

namespace ricochet {
namespace {

// A token as shown in a message: printable ASCII only, at most 32 characters.
std::string printable(std::string_view text) {
  std::string shown;
  for (char c : text.substr(0, 32)) shown += (c >= 32 && c < 127) ? c : '?';
  if (text.size() > 32) shown += "...";
  return shown;
}

// Splits the file into blank-separated tokens, tracking line numbers. A double-quoted string
// on one line is one token (without its quotes). Every read consumes input or throws, so no
// count in the file can make the reader loop without end.
class Lexer {
 public:
  Lexer(std::string name, std::string text) : name_(std::move(name)), text_(std::move(text)) {}

  [[noreturn]] void fail(int line, const std::string& what) const {
    throw InputError(name_ + ":" + std::to_string(line) + ": " + what);
  }
  [[noreturn]] void fail_file(const std::string& what) const {
    throw InputError(name_ + ": " + what);
  }
  int line() const { return line_of_last_; }

  // The next token, or false at the end of the file.
  bool next(std::string_view& token) {
    while (pos_ < text_.size() && is_blank(text_[pos_])) {
      if (text_[pos_] == '\n') ++line_;
      ++pos_;
    }
    if (pos_ == text_.size()) return false;
    line_of_last_ = line_;
    std::size_t begin = pos_, end = pos_;
    if (text_[pos_] == '"') {
      end = text_.find_first_of("\"\n", pos_ + 1);
      if (end == std::string::npos || text_[end] != '"') fail(line_, "unterminated quoted string");
      ++begin;
      pos_ = end + 1;
    } else {
      while (end < text_.size() && !is_blank(text_[end])) ++end;
      pos_ = end;
    }
    token = std::string_view(text_).substr(begin, end - begin);
    return true;
  }

  std::string_view take(std::string_view section) {
    std::string_view token;
    if (!next(token))
      fail(line_of_last_, "unexpected end of file in " + std::string(section) + " (truncated?)");
    return token;
  }

  long long integer(std::string_view section, const std::string& what, long long min,
                    long long max = std::numeric_limits<long long>::max()) {
    const std::string_view t = take(section);
    long long v = 0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec != std::errc() || end != t.data() + t.size()) expected(t, what + " (an integer)");
    if (v < min || v > max) {
      const std::string range =
          max == std::numeric_limits<long long>::max()
              ? ">= " + std::to_string(min)
              : "in [" + std::to_string(min) + ", " + std::to_string(max) + "]";
      fail(line(), what + " must be " + range + " (got " + std::to_string(v) + ")");
    }
    return v;
  }

  double real(std::string_view section, const std::string& what) {
    const std::string_view t = take(section);
    double v = 0.0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec != std::errc() || end != t.data() + t.size() || !std::isfinite(v))
      expected(t, what + " (a finite number)");
    return v;
  }

  void keyword(std::string_view section, std::string_view word) {
    const std::string_view t = take(section);
    if (t != word) expected(t, std::string(word));
  }

  [[noreturn]] void expected(std::string_view got, const std::string& what) const {
    std::string hint;
    if (!got.empty() && got.front() == '$') hint = " (section shorter than its counts say?)";
    fail(line(), "expected " + what + ", got '" + printable(got) + "'" + hint);
  }

 private:
  static bool is_blank(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
  }

  std::string name_, text_;
  std::size_t pos_ = 0;
  int line_ = 1, line_of_last_ = 1;
};

struct RawNode {
  double x, y, z;
  int line;
};

// An element of type 15, 1, 2, 3 (and in 3D 4 or 5). `group` is its physical tag in 2.2 (0 =
// none) or its entity tag in 4.1.
struct RawElement {
  long long tag;
  int type, dim, line;
  std::size_t count;  // nodes used in `nodes`
  long long group;
  std::array<long long, 8> nodes;
};

// Nodes per element type that a reader can take (15, 1, 2, 3, 4, 5), or 0 for any other type.
std::size_t nodes_of_type(long long type) {
  switch (type) {
    case 15:
      return 1;
    case 1:
      return 2;
    case 2:
      return 3;
    case 3:
    case 4:
      return 4;
    case 5:
      return 8;
    default:
      return 0;
  }
}

int dim_of_type(long long type) {
  return type == 15 ? 0 : type == 1 ? 1 : type == 4 || type == 5 ? 3 : 2;
}

// What a reader takes: its cells' dimension, the element types it accepts (cells and node-set
// elements), and the texts of its messages about them.
struct Flavour {
  int cell_dim;
  std::set<long long> types;
  const char* allowed;   // after "unsupported element type T (name); allowed: "
  const char* no_cells;  // after "no cells: the mesh needs "
};

const Flavour kPlanar = {2, {15, 1, 2, 3},
                         "2 (3-node triangle), 3 (4-node quadrangle), and 1/15 for node sets",
                         "elements of type 2 (3-node triangle) or 3 (4-node quadrangle)"};
const Flavour kSolid = {3, {15, 1, 2, 3, 4, 5},
                       "4 (4-node tetrahedron), 5 (8-node hexahedron), and 1/2/3/15 for node sets",
                       "elements of type 4 (4-node tetrahedron) or 5 (8-node hexahedron)"};

std::string type_name(long long type) {
  static const std::map<long long, const char*> names = {
      {1, "2-node line"},         {2, "3-node triangle"},      {3, "4-node quadrangle"},
      {4, "4-node tetrahedron"},  {5, "8-node hexahedron"},    {6, "6-node prism"},
      {7, "5-node pyramid"},      {8, "3-node line"},          {9, "6-node triangle"},
      {10, "9-node quadrangle"},  {11, "10-node tetrahedron"}, {12, "27-node hexahedron"},
      {13, "18-node prism"},      {14, "14-node pyramid"},     {15, "1-node point"},
      {16, "8-node quadrangle"},  {17, "20-node hexahedron"},  {18, "15-node prism"},
      {19, "13-node pyramid"},    {20, "9-node triangle"},     {21, "10-node triangle"},
      {22, "12-node triangle"},   {23, "15-node triangle"},    {24, "15-node triangle"},
      {25, "21-node triangle"},   {26, "4-node line"},         {27, "5-node line"},
      {28, "6-node line"},        {29, "20-node tetrahedron"}, {30, "35-node tetrahedron"},
      {31, "56-node tetrahedron"}};
  const auto it = names.find(type);
  return it == names.end() ? "unknown" : it->second;
}

// Reads the sections of a .msh file (read()); then build_planar() or build_solid() makes the
// mesh of its flavour's cells.
class Reader {
 public:
  Reader(Lexer lexer, const Flavour& flavour) : lex_(std::move(lexer)), flavour_(flavour) {}

  void read() {
    read_format();
    std::set<std::string> seen;
    for (std::string_view t; lex_.next(t);) {
      if (t.empty() || t.front() != '$') lex_.expected(t, "a section such as $Nodes");
      const std::string section(t), name = section.substr(1);
      if (!seen.insert(name).second) lex_.fail(lex_.line(), "duplicate section " + section);
      if (name == "PhysicalNames") {
        read_physical_names(section);
      } else if (name == "Entities" && v4_) {
        read_entities(section);
      } else if (name == "Nodes") {
        v4_ ? read_nodes_v4(section) : read_nodes_v2(section);
      } else if (name == "Elements") {
        v4_ ? read_elements_v4(section) : read_elements_v2(section);
      } else {
        skip_section(section);
        continue;
      }
      lex_.keyword(section, "$End" + name);
    }
    if (!seen.count("Nodes")) lex_.fail_file("no $Nodes section");
    if (!seen.count("Elements")) lex_.fail_file("no $Elements section");
  }

  Mesh build_planar() const;
  Mesh3 build_solid() const;
  // Whether an element of the file is a volume cell (a tetrahedron or hexahedron).
  bool has_volume_cells() const {
    for (const RawElement& e : elements_)
      if (dim_of_type(e.type) == 3) return true;
    return false;
  }

 private:
  void read_format() {
    std::string_view t;
    if (!lex_.next(t)) lex_.fail(1, "empty file; expected $MeshFormat");
    if (t != "$MeshFormat") lex_.expected(t, "$MeshFormat (not a Gmsh .msh file?)");
    const std::string section = "$MeshFormat";
    const std::string version = printable(lex_.take(section));
    const int version_line = lex_.line();
    if (lex_.integer(section, "file-type (0 = ASCII)", 0, 1) == 1)
      lex_.fail(lex_.line(), "binary .msh is not supported; save as ASCII");
    if (version != "2.2" && version != "4.1")
      lex_.fail(version_line, "unsupported .msh version '" + version + "'; supported: 2.2 and 4.1");
    v4_ = version == "4.1";
    lex_.integer(section, "data-size", 1);
    lex_.keyword(section, "$EndMeshFormat");
  }

  void skip_section(const std::string& section) {
    const std::string end = "$End" + section.substr(1);
    for (std::string_view t = lex_.take(section); t != end; t = lex_.take(section)) {
    }
  }

  void read_physical_names(const std::string& s) {
    for (long long n = lex_.integer(s, "number of names", 0); n > 0; --n) {
      const long long dim = lex_.integer(s, "physical dimension", 0, 3);
      const long long tag = lex_.integer(s, "physical tag", 1);
      names_[{dim, tag}] = std::string(lex_.take(s));
    }
  }

  void read_entities(const std::string& s) {
    have_entities_ = true;
    long long counts[4];
    for (long long& c : counts) c = lex_.integer(s, "number of entities", 0);
    for (int dim = 0; dim < 4; ++dim) {
      for (long long n = counts[dim]; n > 0; --n) {
        const long long tag = lex_.integer(s, "entity tag", 1);
        for (int k = 0; k < (dim == 0 ? 3 : 6); ++k) lex_.real(s, "entity coordinate");
        std::vector<long long>& phys = entity_phys_[{dim, tag}];
        for (long long p = lex_.integer(s, "number of physical tags", 0); p > 0; --p)
          phys.push_back(lex_.integer(s, "physical tag", 1));
        if (dim == 0) continue;
        for (long long b = lex_.integer(s, "number of bounding entities", 0); b > 0; --b)
          lex_.integer(s, "bounding entity tag", -(1LL << 62));
      }
    }
  }

  void add_node(long long tag, int line, double x, double y, double z) {
    if (!nodes_.emplace(tag, RawNode{x, y, z, line}).second)
      lex_.fail(line, "duplicate node tag " + std::to_string(tag));
  }

  void read_nodes_v2(const std::string& s) {
    for (long long n = lex_.integer(s, "number of nodes", 0); n > 0; --n) {
      const long long tag = lex_.integer(s, "node tag", 1);
      const int line = lex_.line();
      const double x = lex_.real(s, "x"), y = lex_.real(s, "y"), z = lex_.real(s, "z");
      add_node(tag, line, x, y, z);
    }
  }

  void read_nodes_v4(const std::string& s) {
    const long long blocks = lex_.integer(s, "number of node blocks", 0);
    const int header_line = lex_.line();
    const long long total = lex_.integer(s, "number of nodes", 0);
    lex_.integer(s, "minimum node tag", 0);
    lex_.integer(s, "maximum node tag", 0);
    long long read = 0;
    std::vector<long long> tags;
    for (long long b = 0; b < blocks; ++b) {
      const long long dim = lex_.integer(s, "entity dimension", 0, 3);
      lex_.integer(s, "entity tag", 1);
      const long long parametric = lex_.integer(s, "parametric flag", 0, 1);
      const long long count = lex_.integer(s, "number of nodes in block", 0);
      const long long extra = parametric != 0 ? dim : 0;
      tags.clear();
      for (long long k = 0; k < count; ++k) tags.push_back(lex_.integer(s, "node tag", 1));
      for (const long long tag : tags) {
        const double x = lex_.real(s, "x");
        const int line = lex_.line();
        const double y = lex_.real(s, "y"), z = lex_.real(s, "z");
        for (long long k = 0; k < extra; ++k) lex_.real(s, "parametric coordinate");
        add_node(tag, line, x, y, z);
      }
      read += count;
    }
    if (read != total)
      lex_.fail(header_line, "$Nodes says " + std::to_string(total) + " nodes, its blocks hold " +
                                 std::to_string(read));
  }

  // Checks an element type; returns its node count.
  std::size_t check_type(long long type, int line) const {
    if (!flavour_.types.count(type))
      lex_.fail(line, "unsupported element type " + std::to_string(type) + " (" + type_name(type) +
                          "); allowed: " + flavour_.allowed);
    return nodes_of_type(type);
  }

  void read_element_nodes(const std::string& s, RawElement& e) {
    if (!element_tags_.insert(e.tag).second)
      lex_.fail(e.line, "duplicate element tag " + std::to_string(e.tag));
    for (std::size_t k = 0; k < e.count; ++k) e.nodes[k] = lex_.integer(s, "node tag", 1);
    elements_.push_back(e);
  }

  void read_elements_v2(const std::string& s) {
    elements_line_ = lex_.line();
    for (long long n = lex_.integer(s, "number of elements", 0); n > 0; --n) {
      RawElement e{};
      e.tag = lex_.integer(s, "element tag", 1);
      e.line = lex_.line();
      const long long type = lex_.integer(s, "element type", 1);
      e.count = check_type(type, e.line);
      e.type = static_cast<int>(type);
      e.dim = dim_of_type(type);
      const long long tags = lex_.integer(s, "number of tags", 0);
      for (long long k = 0; k < tags; ++k) {
        const long long tag = lex_.integer(s, "physical or entity tag", -(1LL << 62));
        if (k == 0) e.group = tag;
      }
      read_element_nodes(s, e);
    }
  }

  void read_elements_v4(const std::string& s) {
    elements_line_ = lex_.line();
    const long long blocks = lex_.integer(s, "number of element blocks", 0);
    const long long total = lex_.integer(s, "number of elements", 0);
    lex_.integer(s, "minimum element tag", 0);
    lex_.integer(s, "maximum element tag", 0);
    long long read = 0;
    for (long long b = 0; b < blocks; ++b) {
      RawElement e{};
      e.dim = static_cast<int>(lex_.integer(s, "entity dimension", 0, 3));
      const int line = lex_.line();
      e.group = lex_.integer(s, "entity tag", 1);
      const long long type = lex_.integer(s, "element type", 1);
      e.count = check_type(type, line);
      e.type = static_cast<int>(type);
      if (e.dim != dim_of_type(type))
        lex_.fail(line, "element type " + std::to_string(type) +
                            " in a block of entity dimension " + std::to_string(e.dim));
      const long long count = lex_.integer(s, "number of elements in block", 0);
      for (long long k = 0; k < count; ++k) {
        e.tag = lex_.integer(s, "element tag", 1);
        e.line = lex_.line();
        read_element_nodes(s, e);
      }
      read += count;
    }
    if (read != total)
      lex_.fail(elements_line_, "$Elements says " + std::to_string(total) +
                                    " elements, its blocks hold " + std::to_string(read));
  }

  std::vector<const RawElement*> cells() const;
  static std::map<long long, int> node_index(const std::vector<const RawElement*>& cells);
  void number_nodes(const std::map<long long, int>& index, Mesh& mesh) const;
  void add_cells(const std::vector<const RawElement*>& cells, const std::map<long long, int>& index,
                 Mesh& mesh) const;
  void add_cells(const std::vector<const RawElement*>& cells, const std::map<long long, int>& index,
                 Mesh3& mesh) const;
  template <class M>
  void add_node_sets(const std::map<long long, int>& index, M& mesh) const;
  std::vector<long long> physical_tags(const RawElement& e) const;

  Lexer lex_;
  const Flavour& flavour_;
  bool v4_ = false, have_entities_ = false;
  int elements_line_ = 0;
  std::map<std::pair<long long, long long>, std::string> names_;  // (dim, physical tag)
  std::map<std::pair<long long, long long>, std::vector<long long>> entity_phys_;  // (dim, entity)
  std::map<long long, RawNode> nodes_;                                             // by node tag
  std::vector<RawElement> elements_;
  std::set<long long> element_tags_;
};

// Physical tags of an element.
std::vector<long long> Reader::physical_tags(const RawElement& e) const {
  if (!v4_) return e.group > 0 ? std::vector<long long>{e.group} : std::vector<long long>{};
  const auto it = entity_phys_.find({e.dim, e.group});
  if (it != entity_phys_.end()) return it->second;
  if (have_entities_)
    lex_.fail(e.line, "element " + std::to_string(e.tag) + " belongs to entity (dimension " +
                          std::to_string(e.dim) + ", tag " + std::to_string(e.group) +
                          "), which is not in $Entities");
  return {};
}

// The cells (elements of the flavour's dimension) in element-tag order, each distinct (type,
// node list) once; checks that every element's nodes exist and that there are cells.
std::vector<const RawElement*> Reader::cells() const {
  for (const RawElement& e : elements_) {
    for (std::size_t k = 0; k < e.count; ++k) {
      if (!nodes_.count(e.nodes[k]))
        lex_.fail(e.line, "element " + std::to_string(e.tag) + " refers to node " +
                              std::to_string(e.nodes[k]) + ", which is not in $Nodes");
    }
  }
  // Cells in element-tag order, each distinct (type, node list) once.
  std::vector<const RawElement*> cells;
  for (const RawElement& e : elements_)
    if (e.dim == flavour_.cell_dim) cells.push_back(&e);
  std::sort(cells.begin(), cells.end(),
            [](const RawElement* a, const RawElement* b) { return a->tag < b->tag; });
  std::set<std::pair<int, std::array<long long, 8>>> distinct;
  std::erase_if(cells, [&](const RawElement* e) {
    return !distinct.insert({e->type, e->nodes}).second;
  });
  if (cells.empty()) lex_.fail(elements_line_, std::string("no cells: the mesh needs ") + flavour_.no_cells);
  return cells;
}

// The node index of each node tag used by `cells`: 0, 1, ... in increasing tag.
std::map<long long, int> Reader::node_index(const std::vector<const RawElement*>& cells) {
  std::map<long long, int> index;
  for (const RawElement* e : cells)
    for (std::size_t k = 0; k < e->count; ++k) index[e->nodes[k]] = 0;
  int next = 0;
  for (auto& [tag, i] : index) i = next++;
  return index;
}

Mesh Reader::build_planar() const {
  const std::vector<const RawElement*> cell_list = cells();
  const std::map<long long, int> index = node_index(cell_list);
  Mesh mesh;
  number_nodes(index, mesh);
  add_cells(cell_list, index, mesh);
  add_node_sets(index, mesh);
  return mesh;
}

Mesh3 Reader::build_solid() const {
  const std::vector<const RawElement*> cell_list = cells();
  const std::map<long long, int> index = node_index(cell_list);
  Mesh3 mesh;
  mesh.nodes.resize(3, static_cast<Eigen::Index>(index.size()));
  for (const auto& [tag, i] : index) {
    const RawNode& n = nodes_.at(tag);
    mesh.nodes.col(i) = Vec3(n.x, n.y, n.z);
  }
  add_cells(cell_list, index, mesh);
  add_node_sets(index, mesh);
  return mesh;
}

// Fills mesh.nodes with the nodes of `index` (node-tag order) and checks they lie in z = 0.
void Reader::number_nodes(const std::map<long long, int>& index, Mesh& mesh) const {
  mesh.nodes.resize(2, static_cast<Eigen::Index>(index.size()));
  for (const auto& [tag, i] : index) {
    const RawNode& n = nodes_.at(tag);
    mesh.nodes.col(i) = Vec2(n.x, n.y);
  }
  const Vec2 extent = mesh.nodes.rowwise().maxCoeff() - mesh.nodes.rowwise().minCoeff();
  const double z_tolerance = 1e-12 * extent.maxCoeff();
  for (const auto& [tag, i] : index) {
    const RawNode& n = nodes_.at(tag);
    if (std::abs(n.z) > z_tolerance) {
      std::ostringstream what;
      what << "not a planar mesh in z = 0 (node " << tag << " has z = " << n.z << ")";
      lex_.fail(n.line, what.str());
    }
  }
}

// Appends `cells` to mesh.tris and mesh.quads, all counter-clockwise: either all of them are
// already, or all are clockwise and get flipped; zero-area and non-convex cells are errors.
void Reader::add_cells(const std::vector<const RawElement*>& cells,
                       const std::map<long long, int>& index, Mesh& mesh) const {
  std::vector<std::array<int, 4>> corners(cells.size());
  std::size_t clockwise = 0;
  const RawElement* first_clockwise = nullptr;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    const RawElement& e = *cells[c];
    for (std::size_t k = 0; k < e.count; ++k) corners[c][k] = index.at(e.nodes[k]);
    double longest_squared = 0.0;
    for (std::size_t k = 0; k < e.count; ++k) {
      const Vec2 edge =
          mesh.nodes.col(corners[c][(k + 1) % e.count]) - mesh.nodes.col(corners[c][k]);
      longest_squared = std::max(longest_squared, edge.squaredNorm());
    }
    const double area = signed_area(mesh, corners[c].data(), static_cast<int>(e.count));
    if (!(std::abs(area) > 1e-12 * longest_squared))
      lex_.fail(e.line, "degenerate element " + std::to_string(e.tag) + " (zero area)");
    if (area < 0.0 && clockwise++ == 0) first_clockwise = &e;
  }
  if (clockwise != 0 && clockwise != cells.size())
    lex_.fail(first_clockwise->line, "inverted (clockwise) element " +
                                         std::to_string(first_clockwise->tag) +
                                         "; all cells must have the same orientation");
  for (std::size_t c = 0; c < cells.size(); ++c) {
    const RawElement& e = *cells[c];
    std::array<int, 4>& q = corners[c];
    if (clockwise != 0) std::reverse(q.begin() + 1, q.begin() + static_cast<long>(e.count));
    if (e.count == 3) {
      mesh.tris.push_back({q[0], q[1], q[2]});
    } else if (q4_corner_quality(mesh, q) > 0.0) {
      mesh.quads.push_back(q);
    } else {
      lex_.fail(e.line, "degenerate element " + std::to_string(e.tag) + " (non-convex quadrangle)");
    }
  }
}

// Hexahedra and tetrahedra, each with positive volume in Gmsh's corner order (mesh.hpp); a
// cell of zero volume, negative volume (inverted: not flipped, as a solid mesh has no viewing
// side to choose) or a folded hexahedron is an error.
void Reader::add_cells(const std::vector<const RawElement*>& cells,
                       const std::map<long long, int>& index, Mesh3& mesh) const {
  static constexpr int hex_edges[12][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6},
                                           {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  static constexpr int tet_edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  for (const RawElement* e : cells) {
    std::array<int, 8> c{};
    for (std::size_t k = 0; k < e->count; ++k) c[k] = index.at(e->nodes[k]);
    const bool hex = e->type == 5;
    double longest = 0.0;
    for (const auto& edge : hex ? std::span<const int[2]>(hex_edges) : std::span<const int[2]>(tet_edges))
      longest = std::max(longest, (mesh.nodes.col(c[edge[1]]) - mesh.nodes.col(c[edge[0]])).norm());
    const std::array<int, 4> tet = {c[0], c[1], c[2], c[3]};
    const double volume = hex ? signed_volume(mesh, c) : signed_volume(mesh, tet);
    const std::string element = "element " + std::to_string(e->tag);
    if (!(std::abs(volume) > 1e-12 * longest * longest * longest))
      lex_.fail(e->line, "degenerate " + element + " (zero volume)");
    if (volume < 0.0) {
      std::ostringstream what;
      what << "inverted " << element << " (volume " << volume
           << " < 0); allowed: cells of positive volume in Gmsh's corner order";
      lex_.fail(e->line, what.str());
    }
    if (!hex) {
      mesh.tets.push_back(tet);
    } else if (hex_corner_quality(mesh, c) > 0.0) {
      mesh.hexes.push_back(c);
    } else {
      lex_.fail(e->line, "degenerate " + element + " (a corner Jacobian is <= 0: folded hexahedron)");
    }
  }
}

// Node sets from the physical groups of all elements, restricted to the kept nodes.
template <class M>
void Reader::add_node_sets(const std::map<long long, int>& index, M& mesh) const {
  for (const RawElement& e : elements_) {
    for (const long long phys : physical_tags(e)) {
      const auto name = names_.find({e.dim, phys});
      std::vector<int>& set = mesh.node_sets[name != names_.end() && !name->second.empty()
                                                 ? name->second
                                                 : "physical_" + std::to_string(phys)];
      for (std::size_t k = 0; k < e.count; ++k) {
        const auto it = index.find(e.nodes[k]);
        if (it != index.end()) set.push_back(it->second);
      }
    }
  }
  for (auto& [name, set] : mesh.node_sets) {
    std::sort(set.begin(), set.end());
    set.erase(std::unique(set.begin(), set.end()), set.end());
  }
}

// The text of a .msh file; InputError if it is not a readable regular file.
std::string read_text(const std::filesystem::path& file) {
  const std::string name = file.string();
  std::error_code ec;
  // A device or a pipe (a case's `file = "/dev/zero"`) would be read without end: only a
  // regular file (or a link to one) is a mesh.
  if (std::filesystem::exists(file, ec) && !std::filesystem::is_regular_file(file, ec))
    throw InputError(name + ": cannot open: not a regular file");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(name + ": cannot open");
  std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) throw InputError(name + ": cannot read");
  return text;
}

}  // namespace

Mesh read_gmsh(const std::filesystem::path& file) { return parse_gmsh(read_text(file), file.string()); }

Mesh parse_gmsh(std::string text, const std::string& name) {
  Reader reader(Lexer(name, std::move(text)), kPlanar);
  reader.read();
  return reader.build_planar();
}

int gmsh_dimension(const std::filesystem::path& file) {
  try {
    Reader reader(Lexer(file.string(), read_text(file)), kSolid);
    reader.read();
    return reader.has_volume_cells() ? 3 : 2;
  } catch (const InputError&) {
    return 0;
  }
}

Mesh3 read_gmsh3(const std::filesystem::path& file) { return parse_gmsh3(read_text(file), file.string()); }

Mesh3 parse_gmsh3(std::string text, const std::string& name) {
  Reader reader(Lexer(name, std::move(text)), kSolid);
  reader.read();
  return reader.build_solid();
}

}  // namespace ricochet
