#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>

#include <Eigen/Geometry>

#include "harness/input/case_spec.hpp"
#include "harness/input/gmsh_reader.hpp"
#include "harness/input/run_plan.hpp"
#include "harness/input/suggest.hpp"
#include "harness/input/toml_reader.hpp"
#include "solver/linear/anderson.hpp"
#include "solver/schemes/threads.hpp"

namespace ricochet {
namespace {

constexpr long kMaxDivisions = 100'000;

// A time in seconds as the message shows it, e.g. "1e-06 s".
std::string time_text(double t) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%g s", t);
  return buf;
}

MeshSpec read_mesh(const TableReader& t, const std::string& name, const std::filesystem::path& dir) {
  MeshSpec m;
  m.name = name;
  m.where = t.path();
  if (t.has("file")) {
    std::filesystem::path p = t.text("file");
    if (p.is_relative()) p = dir / p;
    m.source = GmshFile{p};
    // Its cells say (an unreadable file counts as 2D here; building it reports the error).
    m.dimension = gmsh_dimension(p) == 3 ? 3 : 2;
    for (const char* key : {"distort", "seed"})
      if (t.has(key))
        t.fail(key, "applies to generated meshes only (generator = \"rectangle\", \"arc_plate\", \"disk\"), "
                    "not to a mesh file");
  } else {
    const std::string gen = t.choice("generator", "", {"rectangle", "arc_plate", "disk", "box", "ball"});
    if (gen == "box") {
      BoxSpec b;
      b.size = t.vec("size", 3);
      for (int k = 0; k < 3; ++k)
        if (!(b.size[k] > 0.0)) t.fail("size", "each of [lx, ly, lz] must be > 0");
      b.nx = static_cast<int>(t.integer("nx", 1, 1, kMaxDivisions));
      b.ny = static_cast<int>(t.integer("ny", 1, 1, kMaxDivisions));
      b.nz = static_cast<int>(t.integer("nz", 1, 1, kMaxDivisions));
      b.origin = t.vec("origin", 3, Vec3::Zero());
      b.tetrahedra = t.choice("cells", "hex", {"hex", "tet"}) == "tet";
      m.source = b;
      m.dimension = 3;
      if (t.has("distort"))
        t.fail("distort", "applies to the 2D generators (\"rectangle\", \"arc_plate\", \"disk\", also when "
                          "extruded); allowed for \"box\": none");
    } else if (gen == "ball") {
      BallSpec b;
      b.radius = t.number("radius", Range::positive());
      b.center = t.vec("center", 3, Vec3::Zero());
      b.n = static_cast<int>(t.integer("n", 8, 1, kMaxDivisions));
      m.source = b;
      m.dimension = 3;
      if (t.has("distort"))
        t.fail("distort", "applies to the 2D generators (\"rectangle\", \"arc_plate\", \"disk\", also when "
                          "extruded); allowed for \"ball\": none");
    } else if (gen == "rectangle") {
      RectangleSpec r;
      r.width = t.number("width", Range::positive());
      r.height = t.number("height", Range::positive());
      r.nx = static_cast<int>(t.integer("nx", 1, 1, kMaxDivisions));
      r.ny = static_cast<int>(t.integer("ny", 1, 1, kMaxDivisions));
      r.origin = t.vec2("origin", Vec2::Zero());
      r.triangles = t.choice("cells", "quad", {"quad", "tri"}) == "tri";
      m.source = r;
    } else if (gen == "disk") {
      DiskSpec d;
      d.radius = t.number("radius", Range::positive());
      d.center = t.vec2("center", Vec2::Zero());
      d.n = static_cast<int>(t.integer("n", 8, 1, kMaxDivisions));
      m.source = d;
    } else {
      ArcPlateSpec a;
      a.width = t.number("width", Range::positive());
      a.height = t.number("height", Range::positive());
      a.radius = t.number("radius", Range::positive());
      if (!(a.radius > 0.5 * a.width))
        t.fail("radius", "must be > width/2 = " + std::to_string(0.5 * a.width) + " m for the arc to span the plate");
      a.nx = static_cast<int>(t.integer("nx", 12, 1, kMaxDivisions));
      a.ny = static_cast<int>(t.integer("ny", 32, 1, kMaxDivisions));
      a.bias = t.number("bias", 1.0, Range::positive());
      a.height_is_overall = t.choice("height_is", "side", {"side", "overall"}) == "overall";
      a.triangles = t.choice("cells", "quad", {"quad", "tri"}) == "tri";
      m.source = a;
    }
    // Interior nodes moved at random by up to distort x the local element size (distort_mesh).
    if (m.dimension == 2) {
      m.distort = t.number("distort", 0.0, Range{0.0, 0.5, false, true});
      m.seed = static_cast<std::uint64_t>(t.integer("seed", 1, 0, std::numeric_limits<long>::max()));
    }
  }
  // A 2D mesh through a thickness: extrude = {thickness = T, layers = N}.
  if (const auto ex = t.table("extrude")) {
    if (m.dimension == 3)
      t.fail("extrude", "applies to 2D meshes (the 2D generators or a 2D Gmsh file); this mesh is 3D already");
    ExtrusionSpec e;
    e.thickness = ex->number("thickness", Range::positive());
    e.layers = static_cast<int>(ex->integer("layers", 1, 1, kMaxDivisions));
    ex->finish();
    m.extrude = e;
    m.dimension = 3;
  }
  m.scale = t.number("scale", 1.0, Range::positive());
  m.rotate = t.number("rotate", 0.0, Range::closed(-360.0, 360.0));
  if (m.dimension == 3) {
    m.rotate_axis = t.vec("rotate_axis", 3, Vec3::UnitZ());
    if (!(m.rotate_axis.norm() > 0.0)) t.fail("rotate_axis", "must be a non-zero vector");
    m.rotate_axis.normalize();
  } else if (t.has("rotate_axis")) {
    t.fail("rotate_axis", "applies to 3D meshes (a 2D mesh turns about z: rotate and rotate_about)");
  }
  m.rotate_about = t.vec("rotate_about", m.dimension, Vec3::Zero());
  m.offset = t.vec("offset", m.dimension, Vec3::Zero());
  t.finish();
  return m;
}

MaterialSpec read_material(const TableReader& t) {
  MaterialSpec m;
  m.model = t.choice("model", "saint_venant_kirchhoff",
                     {"saint_venant_kirchhoff", "neo_hookean", "blatz_ko", "mooney_rivlin"});
  if (m.model == "blatz_ko") {
    m.shear_modulus = t.number("shear_modulus", Range::positive());
  } else if (m.model == "mooney_rivlin") {
    m.c10 = t.number("c10", Range::non_negative());
    m.c01 = t.number("c01", Range::non_negative());
    if (!(m.c10 + m.c01 > 0.0)) t.fail("c01", "c10 + c01 must be > 0 (small-strain shear modulus 2 (c10 + c01))");
    m.bulk_modulus = t.number("bulk_modulus", Range::positive());
  } else {
    m.young = t.number("young", Range::positive());
    m.poisson = t.number("poisson", Range{-1.0, 0.5, true, true});
  }
  m.density = t.number("density", Range::positive());
  t.finish();
  return m;
}

BodySpec read_body(const TableReader& t, int index, const std::string& default_mesh, int dim) {
  BodySpec b;
  b.where = t.path();
  b.name = t.text("name", "body" + std::to_string(index));
  b.mesh = t.text("mesh", default_mesh);
  if (b.mesh.empty()) t.fail("mesh", "missing: name a mesh of [meshes] here or set the top-level key 'mesh'");
  if (dim == 2) {
    b.element = t.choice("element", "q4", {"q4", "q4_hourglass"});
    b.thickness = t.number("thickness", 1.0, Range::positive());
    b.angular_velocity.z() = t.number("angular_velocity", 0.0, Range{});
  } else {
    b.element = t.choice("element", "hex8", {"hex8", "hex8_hourglass"});
    if (t.has("thickness"))
      t.fail("thickness", "applies to 2D bodies (a 3D body's mesh has its own thickness: extrude = {thickness, layers})");
    b.angular_velocity = t.vec("angular_velocity", 3, Vec3::Zero());
  }
  b.velocity = t.vec("velocity", dim, Vec3::Zero());
  if (t.has("rotation_center")) b.rotation_center = t.vec("rotation_center", dim);
  const auto mat = t.table("material");
  if (!mat) t.fail("material", "missing required table [bodies.material]");
  b.material = read_material(*mat);
  if (const auto hg = t.table("hourglass")) {
    b.hourglass.form = hg->choice("form", "viscous", {"viscous", "stiffness"}) == "viscous"
                           ? HourglassForm::viscous
                           : HourglassForm::stiffness;
    b.hourglass.coeff = hg->number("coeff", 0.1, Range::closed(0.0, 1.0));
    hg->finish();
  }
  for (const auto& ns : t.tables("node_sets")) {
    BoxNodeSet s;
    s.name = ns.text("name");
    const std::vector<double> box = ns.numbers("box", Range{});
    if (dim == 2) {
      if (box.size() != 4 || !(box[0] <= box[2]) || !(box[1] <= box[3]))
        ns.fail("box", "expected [xmin, ymin, xmax, ymax] with xmin <= xmax and ymin <= ymax");
      s.lo = Vec3(box[0], box[1], 0.0);
      s.hi = Vec3(box[2], box[3], 0.0);
    } else {
      if (box.size() != 6 || !(box[0] <= box[3]) || !(box[1] <= box[4]) || !(box[2] <= box[5]))
        ns.fail("box", "expected [xmin, ymin, zmin, xmax, ymax, zmax] with each min <= its max");
      s.lo = Vec3(box[0], box[1], box[2]);
      s.hi = Vec3(box[3], box[4], box[5]);
    }
    ns.finish();
    b.node_sets.push_back(s);
  }
  t.finish();
  return b;
}

BoundarySpec read_boundary(const TableReader& t, const std::string& first_body, int dim) {
  BoundarySpec b;
  b.where = t.path();
  b.body = t.text("body", first_body);
  b.nodes = t.text("nodes");
  b.kind = t.choice("type", "velocity", {"velocity", "displacement"}) == "velocity"
               ? PrescribedDof::Kind::velocity
               : PrescribedDof::Kind::displacement;
  if (t.has("x")) b.x = t.number("x", Range{});
  if (t.has("y")) b.y = t.number("y", Range{});
  t.number("x", 0.0, Range{});  // marks x and y as known keys when absent
  t.number("y", 0.0, Range{});
  if (dim == 3) {
    if (t.has("z")) b.z = t.number("z", Range{});
    t.number("z", 0.0, Range{});
  }
  b.ramp = t.number("ramp", 0.0, Range::non_negative());
  if (!b.x && !b.y && !b.z)
    t.fail("x", dim == 2 ? "missing: give x, y or both (a prescribed value per direction)"
                         : "missing: give at least one of x, y, z (a prescribed value per direction)");
  t.finish();
  return b;
}

InitialVelocitySpec read_initial_velocity(const TableReader& t, const std::string& first_body, int dim) {
  InitialVelocitySpec v;
  v.where = t.path();
  v.body = t.text("body", first_body);
  v.nodes = t.text("nodes");
  v.velocity = t.vec("velocity", dim, Vec3::Zero());
  if (!t.has("velocity"))
    t.fail("velocity", std::string("missing required key: the nodes' initial velocity ") +
                           (dim == 2 ? "[x, y]" : "[x, y, z]") + " in m/s");
  t.finish();
  return v;
}

// A name that prefixes CSV columns (probes, contact interfaces): letters, digits and '_'.
void check_column_name(const TableReader& t, const std::string& name) {
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_'))
      t.fail("name", "got \"" + name + "\"; allowed: letters, digits and '_' (it names CSV columns)");
  if (name.empty()) t.fail("name", "must not be empty (it names CSV columns)");
}

LoadSpec read_load(const TableReader& t, const std::string& first_body, int dim) {
  LoadSpec l;
  l.where = t.path();
  l.body = t.text("body", first_body);
  l.nodes = t.text("nodes");
  if (!t.has("force"))
    t.fail("force", std::string("missing required key: the total force ") + (dim == 2 ? "[x, y]" : "[x, y, z]") +
                        " in N on the node set");
  l.force = t.vec("force", dim);
  l.by_mass = t.choice("distribution", "mass", {"mass", "equal"}) == "mass";
  l.start = t.number("start", 0.0, Range::non_negative());
  l.ramp = t.number("ramp", 0.0, Range::non_negative());
  t.finish();
  return l;
}

ProbeSpec read_probe(const TableReader& t, const std::string& first_body, int dim) {
  ProbeSpec p;
  p.where = t.path();
  p.name = t.text("name");
  check_column_name(t, p.name);
  p.body = t.text("body", first_body);
  if (t.has("point")) p.point = t.vec("point", dim);
  p.node_set = t.text("node_set", "");
  if (p.point.has_value() == !p.node_set.empty())
    t.fail("point", "give exactly one of 'point' (nearest node) or 'node_set' (its first node)");
  t.finish();
  return p;
}

// The vertices of a polyline, `points = [[x, y], ...]`, from the raw TOML node (TableReader
// reads single pairs only). Errors name the key and its line through t.fail().
std::vector<Vec2, Eigen::aligned_allocator<Vec2>> read_points(const TableReader& t, const toml::node* n) {
  if (!n) t.fail("points", "missing required key for type = \"polyline\" (the vertices [[x, y], ...])");
  const toml::array* a = n->as_array();
  if (!a) t.fail("points", "expected an array of points [[x, y], ...]");
  std::vector<Vec2, Eigen::aligned_allocator<Vec2>> pts;
  for (std::size_t i = 0; i < a->size(); ++i) {
    const toml::array* q = (*a)[i].as_array();
    if (!q || q->size() != 2 || !(*q)[0].is_number() || !(*q)[1].is_number())
      t.fail("points", "element " + std::to_string(i) + ": expected a point [x, y] of two numbers");
    const std::optional<double> x = exact_number((*q)[0]), y = exact_number((*q)[1]);
    if (!x || !y)
      t.fail("points", "element " + std::to_string(i) + ": an integer beyond +-2^53 = 9007199254740992 (write it with an exponent)");
    const Vec2 v(*x, *y);
    if (!v.allFinite()) t.fail("points", "element " + std::to_string(i) + ": expected finite numbers");
    if (!pts.empty() && !((v - pts.back()).norm() > 0.0))
      t.fail("points", "elements " + std::to_string(i - 1) + " and " + std::to_string(i) +
                           " coincide (zero-length segment)");
    pts.push_back(v);
  }
  if (pts.size() < 2)
    t.fail("points", "a polyline needs at least 2 points; got " + std::to_string(pts.size()));
  return pts;
}

// An obstacle's friction keys, then its keys checked against those of its type, `keys`
// (TableReader::finish() would not know `points` or `axes`, read from the raw node).
void read_obstacle_friction_and_keys(const TableReader& t, ObstacleSpec& o, const std::string& type,
                                     const std::vector<std::string>& keys) {
  o.friction = t.number("friction", 0.0, Range::non_negative());
  if (const auto by_body = t.table("friction_by_body")) {
    for (const auto& body : by_body->keys()) o.friction_by_body[body] = by_body->number(body, Range::non_negative());
    by_body->finish();
  }
  for (const auto& key : t.keys()) {
    if (std::find(keys.begin(), keys.end(), key) != keys.end()) continue;
    std::string allowed;
    for (const auto& k : keys) allowed += (allowed.empty() ? "" : ", ") + k;
    t.fail(key, "unknown key for type = \"" + type + "\"" + did_you_mean(key, keys) + "; allowed here: " + allowed);
  }
}

// `raw_points`: the obstacle's `points` node, if any (read from the document directly).
ObstacleSpec read_obstacle(const TableReader& t, int index, const toml::node* raw_points) {
  ObstacleSpec o;
  o.where = t.path();
  o.name = t.text("name", "obstacle" + std::to_string(index));
  check_column_name(t, o.name);
  const std::string type = t.choice("type", "line", {"line", "circle", "polyline"});
  std::vector<std::string> keys{"name", "type", "friction", "friction_by_body"};
  if (type == "line") {
    o.point = t.vec2("point", Vec2::Zero());
    o.normal = t.vec2("normal");
    if (!(o.normal.norm() > 0.0)) t.fail("normal", "must be a non-zero vector (the outward normal)");
    o.normal.normalize();
    o.shape.kind = ObstacleKind::line;
    o.shape.point = o.point;
    o.shape.normal = o.normal;
    keys.insert(keys.end(), {"point", "normal"});
  } else if (type == "circle") {
    o.shape.kind = ObstacleKind::circle;
    o.shape.center = t.vec2("center");
    o.shape.radius = t.number("radius", Range::positive());
    o.shape.inside = t.boolean("inside", false);
    keys.insert(keys.end(), {"center", "radius", "inside"});
  } else {
    o.shape.kind = ObstacleKind::polyline;
    o.shape.points = read_points(t, raw_points);
    o.shape.left = t.choice("side", "left", {"left", "right"}) == "left";
    keys.insert(keys.end(), {"points", "side"});
  }
  o.shape.name = o.name;
  read_obstacle_friction_and_keys(t, o, type, keys);
  if (const std::string e = obstacle_error(o.shape); !e.empty()) t.fail("type", e);
  return o;
}

// A 3D obstacle (docs/case-format.md, 3D cases): plane, sphere, box or cylinder. `raw_axes`: the
// box's `axes` node, if any (an array of two [x, y, z], read from the document directly).
ObstacleSpec read_obstacle3(const TableReader& t, int index, const toml::node* raw_axes) {
  ObstacleSpec o;
  o.where = t.path();
  o.name = t.text("name", "obstacle" + std::to_string(index));
  check_column_name(t, o.name);
  const std::string type = t.choice("type", "plane", {"plane", "sphere", "box", "cylinder"});
  std::vector<std::string> keys{"name", "type", "friction", "friction_by_body"};
  auto positive = [&](const char* key) {
    const Vec3 v = t.vec(key, 3);
    for (int k = 0; k < 3; ++k)
      if (!(v[k] > 0.0)) t.fail(key, "each of its three values must be > 0");
    return v;
  };
  try {
    if (type == "plane") {
      const Vec3 point = t.vec("point", 3, Vec3::Zero());
      const Vec3 normal = t.vec("normal", 3);
      if (!(normal.norm() > 0.0)) t.fail("normal", "must be a non-zero vector (the outward normal)");
      o.shape3 = make_plane_obstacle3(o.name, point, normal);
      keys.insert(keys.end(), {"point", "normal"});
    } else if (type == "sphere") {
      o.shape3 = make_sphere_obstacle3(o.name, t.vec("center", 3), t.number("radius", Range::positive()),
                                       t.boolean("inside", false));
      keys.insert(keys.end(), {"center", "radius", "inside"});
    } else if (type == "box") {
      Vec3 axis[2] = {Vec3::UnitX(), Vec3::UnitY()};
      if (raw_axes) {
        const toml::array* a = raw_axes->as_array();
        if (!a || a->size() != 2) t.fail("axes", "expected two directions [[x, y, z], [x, y, z]]");
        for (int k = 0; k < 2; ++k) {
          const toml::array* q = (*a)[static_cast<std::size_t>(k)].as_array();
          if (!q || q->size() != 3) t.fail("axes", "element " + std::to_string(k) + ": expected a direction [x, y, z]");
          for (int d = 0; d < 3; ++d) {
            const std::optional<double> x = exact_number((*q)[static_cast<std::size_t>(d)]);
            if (!x || !std::isfinite(*x)) t.fail("axes", "element " + std::to_string(k) + ": expected three finite numbers");
            axis[k][d] = *x;
          }
          if (!(axis[k].norm() > 0.0)) t.fail("axes", "element " + std::to_string(k) + ": must be a non-zero vector");
        }
      }
      o.shape3 = make_box_obstacle3(o.name, t.vec("center", 3), positive("half_extents"), t.boolean("inside", false),
                                    axis[0], axis[1]);
      keys.insert(keys.end(), {"center", "half_extents", "axes", "inside"});
    } else {
      const Vec3 axis = t.vec("axis", 3);
      if (!(axis.norm() > 0.0)) t.fail("axis", "must be a non-zero vector (the cylinder's axis)");
      const double half_length =
          t.has("half_length") ? t.number("half_length", Range::positive()) : std::numeric_limits<double>::infinity();
      o.shape3 = make_cylinder_obstacle3(o.name, t.vec("center", 3), axis, t.number("radius", Range::positive()),
                                         t.boolean("inside", false), half_length);
      keys.insert(keys.end(), {"center", "axis", "radius", "half_length", "inside"});
    }
  } catch (const std::invalid_argument& e) {
    t.fail("type", e.what());
  }
  read_obstacle_friction_and_keys(t, o, type, keys);
  if (const std::string e = obstacle_error(o.shape3); !e.empty()) t.fail("type", e);
  return o;
}

// A name of the run's scheme in summary.json: letters, digits, '_', '-', '.' (not first).
bool scheme_label_ok(const std::string& s) {
  if (s.empty() || s.size() > 64 || s[0] == '.' || s[0] == '-') return false;
  return std::all_of(s.begin(), s.end(), [](char ch) {
    return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-' || ch == '.';
  });
}

// The shipped adapters: adapters/<name>.py in the adapters folder, by name.
std::vector<std::string> shipped_adapters() {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(shipped_adapters_dir(), ec))
    if (e.path().extension() == ".py" && e.path().stem().string().find('_') != 0) names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

// [external] (docs/peers.md).
ExternalSpec read_external(const TableReader& t) {
  ExternalSpec e;
  const bool has_adapter = t.has("adapter"), has_command = t.has("command");
  if (has_adapter && has_command)
    t.fail("command", "give either external.adapter (a shipped adapter) or external.command (your own), not both");
  if (!has_adapter && !has_command)
    t.fail("adapter", "missing: a shipped adapter's name (external.adapter) or your adapter's argv (external.command = [...]); docs/peers.md");
  if (has_adapter) {
    e.adapter = t.text("adapter");
    const std::vector<std::string> names = shipped_adapters();
    if (std::find(names.begin(), names.end(), e.adapter) == names.end()) {
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
      t.fail("adapter", "no shipped adapter \"" + e.adapter + "\"" + did_you_mean(e.adapter, names) +
                            "; shipped (" + shipped_adapters_dir().string() + "): " + (list.empty() ? "none" : list) +
                            "; or give your own as external.command");
    }
  } else {
    e.command = t.texts("command");
    if (e.command.empty()) t.fail("command", "expected a non-empty array of strings: the adapter program and its first arguments");
    for (const std::string& arg : e.command)
      for (std::size_t at = arg.find('{'); at != std::string::npos; at = arg.find('{', at + 1)) {
        if (arg.compare(at, 2, "{{") == 0) { ++at; continue; }
        const std::size_t end = arg.find('}', at);
        const std::string ph = arg.substr(at, end == std::string::npos ? std::string::npos : end - at + 1);
        if (ph != "{python}" && ph != "{adapters}" && ph != "{case_dir}")
          t.fail("command", "unknown placeholder \"" + ph + "\" in \"" + arg + "\"; allowed: {python}, {adapters}, {case_dir} ({{ for a literal {)");
      }
  }
  e.timeout = t.number("timeout", 3600.0, Range{0.0, 1e7, true, false});
  e.options_json = t.table_as_json("options");
  t.finish();
  return e;
}

}  // namespace

std::filesystem::path shipped_adapters_dir() {
  const char* dir = std::getenv("RICOCHET_ADAPTERS");
  return dir && *dir ? std::filesystem::path(dir) : std::filesystem::path(RICOCHET_ADAPTERS_DIR);
}

static CaseSpec read_case_document(toml::table doc, const std::string& file,
                                   const std::vector<std::string>& overrides) {
  CaseContext ctx{file, {}};
  CaseSpec c;
  c.file = file;
  c.overrides = overrides;
  for (const auto& o : overrides) ctx.overridden.insert(apply_override(doc, file, o));

  const TableReader root(doc, "", ctx);
  c.name = root.text("name", std::filesystem::path(file).stem().string());
  c.description = root.text("description", "");
  // One of ricochet's own schemes, or the name of an external one (docs/peers.md), which then
  // needs an [external] table (below).
  const std::string scheme_text = root.text("scheme", "explicit");
  const std::vector<std::string> own_schemes = {"explicit", "semi_explicit", "implicit", "explicit_penalty"};
  if (std::find(own_schemes.begin(), own_schemes.end(), scheme_text) != own_schemes.end()) {
    c.scheme = scheme_from_name(scheme_text);
  } else {
    if (!root.has("external"))
      root.fail("scheme", "\"" + scheme_text + "\" is not one of ricochet's schemes" + did_you_mean(scheme_text, own_schemes) +
                              "; allowed: explicit, semi_explicit, implicit, explicit_penalty, or the name of an external "
                              "scheme given with an [external] table (docs/peers.md)");
    if (!scheme_label_ok(scheme_text))
      root.fail("scheme", "\"" + scheme_text + "\": an external scheme's name has letters, digits, '_', '-', '.' (not first), at most 64 characters");
    c.scheme = Scheme::external;
  }
  c.default_mesh = root.text("mesh", "");
  c.threads = static_cast<int>(root.integer("threads", 0, 0, kMaxThreads));
  c.adapt_threads = root.boolean("adapt_threads", true);

  const std::filesystem::path dir = std::filesystem::path(file).parent_path();
  const auto meshes = root.table("meshes");
  if (!meshes) root.fail("meshes", "missing required table [meshes.NAME]");
  for (const auto& name : meshes->keys()) {
    const auto mt = meshes->table(name);
    c.meshes.emplace(name, read_mesh(*mt, name, dir));
  }
  meshes->finish();
  if (c.meshes.empty()) root.fail("meshes", "define at least one mesh as [meshes.NAME]");
  // The case's dimension is its meshes': all 2D or all 3D.
  c.dimension = c.meshes.begin()->second.dimension;
  for (const auto& [name, m] : c.meshes)
    if (m.dimension != c.dimension) {
      const auto& first = *c.meshes.begin();
      const TableReader mt = *meshes->table(name);
      mt.fail(mt.has("file") ? "file" : "generator", "a " + std::to_string(m.dimension) + "D mesh in a case whose mesh \"" + first.first + "\" is " +
                           std::to_string(c.dimension) + "D; a case is 2D or 3D throughout (a 2D mesh becomes 3D "
                           "with extrude = {thickness, layers})");
    }
  if (c.dimension == 2) {
    c.plane = root.choice("plane", "stress", {"stress", "strain"}) == "stress" ? PlaneMode::stress : PlaneMode::strain;
  } else {
    if (root.has("plane"))
      root.fail("plane", "applies to 2D cases (plane stress or strain); this case's meshes are 3D");
  }
  c.gravity = root.vec("gravity", c.dimension, Vec3::Zero());
  // A mesh name that is not defined: say which are, and the likely one.
  auto unknown_mesh = [&](const std::string& name) {
    std::vector<std::string> names;
    std::string defined;
    for (const auto& [n, m] : c.meshes) {
      names.push_back(n);
      defined += (defined.empty() ? "" : ", ") + n;
    }
    return "no mesh named \"" + name + "\" in [meshes]" + did_you_mean(name, names) + "; defined: " + defined;
  };
  if (!c.default_mesh.empty() && !c.meshes.count(c.default_mesh)) root.fail("mesh", unknown_mesh(c.default_mesh));

  const auto bodies = root.tables("bodies");
  if (bodies.empty()) root.fail("bodies", "missing: define at least one [[bodies]]");
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    BodySpec b = read_body(bodies[i], static_cast<int>(i), c.default_mesh, c.dimension);
    if (!c.meshes.count(b.mesh)) bodies[i].fail("mesh", unknown_mesh(b.mesh));
    for (const auto& other : c.bodies)
      if (other.name == b.name) bodies[i].fail("name", "duplicate body name \"" + b.name + "\"");
    c.bodies.push_back(std::move(b));
  }
  const std::string first_body = c.bodies.front().name;
  for (const auto& t : root.tables("boundary")) c.boundaries.push_back(read_boundary(t, first_body, c.dimension));
  for (const auto& t : root.tables("initial_velocity"))
    c.initial_velocities.push_back(read_initial_velocity(t, first_body, c.dimension));
  for (const auto& t : root.tables("loads")) c.loads.push_back(read_load(t, first_body, c.dimension));
  if (const auto sr = root.table("scene_rotation")) {
    if (c.dimension != 3)
      root.fail("scene_rotation", "applies to 3D cases (a 2D mesh turns in its plane: meshes.NAME.rotate)");
    const Vec3 axis = sr->vec("axis", 3);
    if (!(axis.norm() > 0.0)) sr->fail("axis", "must be a non-zero vector (the rotation's axis)");
    const double angle = sr->number("angle", Range::closed(-360.0, 360.0));
    sr->finish();
    if (!c.boundaries.empty())
      sr->fail("axis", "a case with [[boundary]] cannot be turned: its x, y, z are fixed global directions");
    c.scene_rotation = Eigen::AngleAxisd(angle * std::numbers::pi / 180.0, axis.normalized()).toRotationMatrix();
  }
  if (const auto rx = root.table("relaxation")) {
    c.relaxation.enabled = rx->boolean("enabled", true);
    c.relaxation.tolerance = rx->number("tolerance", 1e-6, Range{0.0, 0.1, true, false});
    c.relaxation.max_steps = rx->integer("max_steps", 100000, 1, 100'000'000);
    rx->finish();
  }

  const auto obstacles = root.tables("obstacles");
  for (std::size_t i = 0; i < obstacles.size(); ++i) {
    if (c.dimension == 2) {
      const toml::node* raw_points = doc["obstacles"][i]["points"].node();
      c.obstacles.push_back(read_obstacle(obstacles[i], static_cast<int>(i), raw_points));
    } else {
      const toml::node* raw_axes = doc["obstacles"][i]["axes"].node();
      c.obstacles.push_back(read_obstacle3(obstacles[i], static_cast<int>(i), raw_axes));
    }
    for (const auto& [body, mu] : c.obstacles.back().friction_by_body) {
      bool known = false;
      for (const auto& b : c.bodies) known = known || b.name == body;
      if (!known) obstacles[i].fail("friction_by_body", "no body named \"" + body + "\"");
    }
  }
  const auto pairs = root.tables("contact_pairs");
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const TableReader& t = pairs[i];
    ContactPairSpec cp;
    cp.where = t.path();
    cp.slave = t.text("slave");
    cp.master = t.text("master");
    cp.friction = t.number("friction", 0.0, Range::non_negative());
    cp.two_pass = t.boolean("two_pass", false);
    cp.name = t.text("name", cp.slave + "_" + cp.master);
    check_column_name(t, cp.name);
    t.finish();
    for (const char* key : {"slave", "master"}) {
      const std::string& name = std::string(key) == "slave" ? cp.slave : cp.master;
      bool known = false;
      for (const auto& b : c.bodies) known = known || b.name == name;
      if (!known) t.fail(key, "no body named \"" + name + "\"");
    }
    if (cp.slave == cp.master) t.fail("master", "must differ from slave (self-contact is not treated)");
    c.contact_pairs.push_back(std::move(cp));
  }
  // Interface names (obstacles and pairs) name history columns: one each.
  {
    std::vector<std::string> seen;
    auto check = [&](const TableReader& t, const std::string& name) {
      if (std::find(seen.begin(), seen.end(), name) != seen.end())
        t.fail("name", "\"" + name + "\" already names another obstacle or contact pair (each names its history columns)");
      seen.push_back(name);
    };
    for (std::size_t i = 0; i < obstacles.size(); ++i) check(obstacles[i], c.obstacles[i].name);
    for (std::size_t i = 0; i < pairs.size(); ++i) check(pairs[i], c.contact_pairs[i].name);
  }
  if ((!c.obstacles.empty() || !c.contact_pairs.empty()) && c.scheme == Scheme::plain_explicit)
    root.fail("scheme", "\"explicit\" has no contact algorithm; cases with [[obstacles]] or [[contact_pairs]] need "
                        "\"semi_explicit\", \"implicit\" or \"explicit_penalty\"");
  if (const auto ext = root.table("external")) {
    if (c.scheme != Scheme::external)
      root.fail("external", std::string("applies to external schemes (a scheme named other than ricochet's own); this case's scheme is \"") +
                                scheme_name(c.scheme) + "\", one of ricochet's own");
    c.external = read_external(*ext);
    c.external.name = scheme_text;
  }
  if (const auto ct = root.table("contact")) {
    c.contact.level = ct->choice("level", "position", {"position", "velocity"}) == "position"
                          ? ContactLevel::position
                          : ContactLevel::velocity;
    c.contact.rho_factor = ct->number("rho_factor", 1.0, Range::open(0.0, 2.0));
    c.contact.tolerance = ct->number("tolerance", 1e-10, Range{0.0, 1e-2, true, false});
    c.contact.max_sweeps = static_cast<int>(ct->integer("max_sweeps", 200, 1, 100000));
    c.contact.frame_updates = static_cast<int>(ct->integer("frame_updates", 0, 0, 100));
    ct->finish();
  }

  if (const auto im = root.table("implicit")) {
    c.implicit.theta = im->number("theta", 0.5, Range::closed(0.5, 1.0));
    c.implicit.xi = im->number("xi", 0.5, Range::closed(0.5, 1.0));
    c.implicit.newton_tolerance = im->number("newton_tolerance", 1e-10, Range{0.0, 1e-2, true, false});
    c.implicit.max_newton_iterations = static_cast<int>(im->integer("max_newton_iterations", 25, 1, 1000));
    c.implicit.linear_tolerance = im->number("linear_tolerance", 1e-12, Range{0.0, 1e-2, true, false});
    c.implicit.max_linear_iterations = static_cast<int>(im->integer("max_linear_iterations", 10000, 1, 10'000'000));
    // "ldlt" (the hand-written LDL^T this replaced) still selects the direct solver, so older
    // case files keep their meaning.
    const std::string solver = im->choice("linear_solver", "auto", {"auto", "pcg", "direct", "ldlt", "mass"});
    c.implicit.linear_solver = solver == "pcg"                          ? LinearSolverKind::pcg
                               : solver == "direct" || solver == "ldlt" ? LinearSolverKind::direct
                               : solver == "mass"                       ? LinearSolverKind::mass
                                                                        : LinearSolverKind::automatic;
    c.implicit.mass_contraction =
        im->number("mass_contraction", ImplicitSettings{}.mass_contraction, Range{0.0, 1.0, false, true});
    c.implicit.mass_iterations =
        static_cast<int>(im->integer("mass_iterations", ImplicitSettings{}.mass_iterations, 1, 1000));
    c.implicit.mass_anderson_depth = static_cast<int>(
        im->integer("mass_anderson_depth", ImplicitSettings{}.mass_anderson_depth, 0, AndersonMixer::kMaxDepth));
    c.implicit.uzawa_sweeps = static_cast<int>(im->integer("uzawa_sweeps", 30, 0, 100000));
    c.implicit.factor_precision = im->choice("factor_precision", "double", {"double", "single"}) == "single"
                                      ? FactorPrecision::single
                                      : FactorPrecision::double_;
    c.implicit.refactor_contraction =
        im->number("refactor_contraction", ImplicitSettings{}.refactor_contraction, Range{0.0, 1.0, false, true});
    c.implicit.refactor_iterations =
        static_cast<int>(im->integer("refactor_iterations", ImplicitSettings{}.refactor_iterations, 0, 1000));
    im->finish();
  }
  if (const auto pe = root.table("penalty")) {
    c.penalty.scale_factor = pe->number("scale_factor", 0.1, Range{0.0, 1e6, true, false});
    // LS-DYNA's SOFT = 1 and SOFSCL (soft_dt is set up from the run's step in case_setup).
    const bool soft = pe->boolean("soft", false);
    const double soft_scale = pe->number("soft_scale", 0.1, Range{0.0, 1.0, true, false});
    c.penalty.soft_scale = soft ? soft_scale : 0.0;
    pe->finish();
  }

  const auto time = root.table("time");
  if (!time) root.fail("time", "missing required table [time] (at least time.end)");
  c.end_time = time->number("end", Range::positive());
  if (time->is_text("dt")) {
    if (time->text("dt") != "auto") time->fail("dt", "expected a number > 0 or \"auto\"; got \"" + time->text("dt") + "\"");
  }
  else if (time->has("dt"))
    c.dt = time->number("dt", Range::positive());
  else
    time->text("dt", "auto");
  c.dt_safety = time->number("safety", 0.9, Range{0.0, 1.0, true, false});
  // The variable step (docs/case-format.md, [time]): the automatic step of the explicit schemes,
  // recomputed every this many steps from the current configuration.
  c.dt_update_interval = static_cast<int>(time->integer("dt_update_interval", 0, 0, 1'000'000'000));
  c.dt_min_ratio = time->number("dt_min_ratio", 0.01, Range{0.0, 1.0, true, false});
  time->finish();
  if (c.dt && *c.dt > c.end_time) time->fail("dt", "must be <= time.end");
  if (c.dt_update_interval > 0 && c.dt)
    time->fail("dt_update_interval", "needs time.dt = \"auto\" (a fixed time.dt is never recomputed); got " +
                                         std::to_string(c.dt_update_interval) + " with time.dt = " + time_text(*c.dt));
  if (c.dt_update_interval > 0 && c.scheme == Scheme::implicit)
    time->fail("dt_update_interval", "the implicit scheme takes a fixed step; allowed: 0 with scheme = \"implicit\", "
                                     "> 0 with \"explicit\", \"semi_explicit\" or \"explicit_penalty\"");

  c.sample_interval = c.end_time / 1000.0;
  if (const auto out = root.table("output")) {
    c.sample_interval = out->number("interval", c.sample_interval, Range::non_negative());
    c.field_times = out->numbers("fields", Range::non_negative());  // times after the end are skipped
    // field_interval: a snapshot every interval from t = 0 to the end, besides `fields` (the
    // run stores the snapshots until it writes them, so their number is bounded).
    if (const double every = out->number("field_interval", 0.0, Range::non_negative()); every > 0.0) {
      constexpr double kMaxSnapshots = 10'000;
      if (c.end_time / every > kMaxSnapshots)
        out->fail("field_interval", "gives " + std::to_string(static_cast<long>(c.end_time / every)) +
                                        " snapshots over time.end; at most 10000 (a larger interval)");
      for (long k = 0; k * every <= c.end_time * (1.0 + 1e-12); ++k) c.field_times.push_back(k * every);
    }
    const std::string measure = out->choice("stress_measure", "cauchy", {"cauchy", "pk2", "kirchhoff"});
    c.stress_measure = measure == "pk2"         ? StressMeasure::pk2
                       : measure == "kirchhoff" ? StressMeasure::kirchhoff
                                                : StressMeasure::cauchy;
    c.stress_every_step = out->boolean("stress_every_step", true);
    // The field files' encoding and compression (docs/outputs.md, fields/*.vtu). Compression
    // applies to binary data: with "ascii" it may only be absent or "none".
    const std::string encoding = out->choice("field_format", "binary", {"ascii", "binary", "base64"});
    c.field_format.encoding = encoding == "ascii"    ? VtuEncoding::ascii
                              : encoding == "base64" ? VtuEncoding::base64
                                                     : VtuEncoding::binary;
    const std::string compression =
        out->choice("field_compression", encoding == "ascii" ? "none" : "zlib", {"none", "zlib"});
    if (encoding == "ascii" && compression != "none")
      out->fail("field_compression", "\"" + compression +
                                         "\" needs field_format \"binary\" or \"base64\"; with \"ascii\" "
                                         "allowed: \"none\" (or leave it out)");
    c.field_format.compression = compression == "zlib" ? VtuCompression::zlib : VtuCompression::none;
    for (const auto& p : out->tables("probes")) {
      c.probes.push_back(read_probe(p, first_body, c.dimension));
      for (std::size_t k = 0; k + 1 < c.probes.size(); ++k)
        if (c.probes[k].name == c.probes.back().name) p.fail("name", "duplicate probe name \"" + c.probes.back().name + "\"");
    }
    out->finish();
  }
  if (const auto dv = root.table("divergence")) {
    c.energy_growth_limit = dv->number("energy_growth", 2.0, Range{1.0, 1e12, true, false});
    c.monitor_every = static_cast<int>(dv->integer("check_every", 50, 1, 1'000'000));
    dv->finish();
  }
  // [limits] (docs/reliability.md): the default memory ceiling is this machine's.
  c.limits.max_memory_gib = default_max_memory_gib();
  if (const auto lim = root.table("limits")) {
    c.limits.max_steps = lim->number("max_steps", c.limits.max_steps, Range::closed(1.0, 1e15));
    c.limits.max_history_rows = lim->number("max_history_rows", c.limits.max_history_rows, Range::closed(1.0, 1e12));
    c.limits.max_memory_gib = lim->number("max_memory", c.limits.max_memory_gib, Range{0.0, 1e6, true, false});
    lim->finish();
  }
  root.finish();
  return c;
}

CaseSpec read_case(const std::string& file, const std::vector<std::string>& overrides) {
  return read_case_document(parse_toml_file(file, "case file"), file, overrides);
}

CaseSpec read_case_text(std::string_view text, const std::string& file,
                        const std::vector<std::string>& overrides) {
  return read_case_document(parse_toml(text, file), file, overrides);
}

const char* scheme_name(Scheme s) {
  switch (s) {
    case Scheme::semi_explicit: return "semi_explicit";
    case Scheme::implicit: return "implicit";
    case Scheme::explicit_penalty: return "explicit_penalty";
    case Scheme::external: return "external";
    case Scheme::plain_explicit: break;
  }
  return "explicit";
}

Scheme scheme_from_name(const std::string& name) {
  if (name == "semi_explicit") return Scheme::semi_explicit;
  if (name == "implicit") return Scheme::implicit;
  if (name == "explicit_penalty") return Scheme::explicit_penalty;
  if (name == "external") return Scheme::external;
  return Scheme::plain_explicit;
}

}  // namespace ricochet
