#include "harness/input/mesh_generators3.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "harness/input/generator_checks.hpp"

namespace ricochet {
namespace {

using generator_checks::fail;
using generator_checks::max_nodes;
using generator_checks::require_positive;
using generator_checks::str;

// The 6 tetrahedra of a hexahedron around its diagonal 0-6, as hexahedron corners (make_box).
constexpr std::array<std::array<int, 4>, 6> kHexTets = {
    {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6}, {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}}};

void sort_unique(std::vector<int>& set) {
  std::sort(set.begin(), set.end());
  set.erase(std::unique(set.begin(), set.end()), set.end());
}

void set_all(Mesh3& mesh) {
  std::vector<int>& all = mesh.node_sets["all"];
  all.resize(static_cast<std::size_t>(mesh.num_nodes()));
  for (int k = 0; k < mesh.num_nodes(); ++k) all[static_cast<std::size_t>(k)] = k;
}

}  // namespace

Mesh3 make_box(const BoxSpec& spec) {
  const char* gen = "box";
  require_positive(gen, "lx", spec.size.x());
  require_positive(gen, "ly", spec.size.y());
  require_positive(gen, "lz", spec.size.z());
  const int n[3] = {spec.nx, spec.ny, spec.nz};
  const char* names[3] = {"nx", "ny", "nz"};
  for (int a = 0; a < 3; ++a)
    if (n[a] < 1) fail(std::string("box: ") + names[a] + " must be >= 1 (got " + std::to_string(n[a]) + ")");
  // Checked product by product: three factors up to 2^31 overflow 64 bits, two do not.
  const long long nodes_xy = (spec.nx + 1LL) * (spec.ny + 1LL);
  const long long nodes_ll = nodes_xy > max_nodes ? max_nodes + 1LL : nodes_xy * (spec.nz + 1LL);
  if (nodes_ll > max_nodes)
    fail("box: (nx+1)*(ny+1)*(nz+1) must be <= " + std::to_string(max_nodes) + " nodes (got nx " +
         std::to_string(spec.nx) + ", ny " + std::to_string(spec.ny) + ", nz " + std::to_string(spec.nz) + ")");
  if (!spec.origin.allFinite())
    fail("box: origin must be finite (got " + str(spec.origin.x()) + ", " + str(spec.origin.y()) + ", " +
         str(spec.origin.z()) + ")");

  const int nx = spec.nx, ny = spec.ny, nz = spec.nz;
  const auto id = [&](int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; };
  Mesh3 mesh;
  mesh.nodes.resize(3, static_cast<Eigen::Index>(nodes_ll));
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        // origin + size (i/n): the far sides are exactly origin + size.
        const int p = id(i, j, k);
        mesh.nodes(0, p) = spec.origin.x() + spec.size.x() * (static_cast<double>(i) / nx);
        mesh.nodes(1, p) = spec.origin.y() + spec.size.y() * (static_cast<double>(j) / ny);
        mesh.nodes(2, p) = spec.origin.z() + spec.size.z() * (static_cast<double>(k) / nz);
      }
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const std::array<int, 8> h = {id(i, j, k),         id(i + 1, j, k),         id(i + 1, j + 1, k),
                                      id(i, j + 1, k),     id(i, j, k + 1),         id(i + 1, j, k + 1),
                                      id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)};
        if (!spec.tetrahedra) {
          mesh.hexes.push_back(h);
        } else {
          for (const auto& t : kHexTets) mesh.tets.push_back({h[t[0]], h[t[1]], h[t[2]], h[t[3]]});
        }
      }

  auto& sets = mesh.node_sets;
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        const int p = id(i, j, k);
        if (i == 0) sets["left"].push_back(p);
        if (i == nx) sets["right"].push_back(p);
        if (j == 0) sets["bottom"].push_back(p);
        if (j == ny) sets["top"].push_back(p);
        if (k == 0) sets["back"].push_back(p);
        if (k == nz) sets["front"].push_back(p);
        if (i == 0 || i == nx || j == 0 || j == ny || k == 0 || k == nz) sets["boundary"].push_back(p);
      }
  set_all(mesh);
  return mesh;
}

Mesh3 make_ball(const BallSpec& spec) {
  require_positive("ball", "radius", spec.radius);
  if (!spec.center.allFinite())
    fail("ball: center must be finite (got " + str(spec.center.x()) + ", " + str(spec.center.y()) + ", " +
         str(spec.center.z()) + ")");
  if (spec.n < 1) fail("ball: n must be >= 1 (got " + std::to_string(spec.n) + ")");
  const long long n_ll = spec.n, nr_ll = (n_ll + 1) / 2;
  // (n+1)^3 overflows 64 bits for n near 2^31: bound n first (max_nodes^(1/3) < 500).
  if (n_ll > 1000 || (n_ll + 1) * (n_ll + 1) * (n_ll + 1) + nr_ll * (6 * n_ll * n_ll + 2) > max_nodes)
    fail("ball: (n+1)^3 + ceil(n/2) (6 n^2 + 2) must be <= " + std::to_string(max_nodes) + " nodes (got n " +
         std::to_string(spec.n) + ")");

  // The core: half-width a = core R, bulged by `bulge` towards the sphere through its corners
  // (the header gives the geometry).
  constexpr double core = 0.4, bulge = 0.3;
  const int n = spec.n, nr = (n + 1) / 2, n1 = n + 1;
  const double R = spec.radius, a = core * R, sqrt3 = std::numbers::sqrt3;
  const auto lattice = [n](int i) { return static_cast<double>(2 * i - n) / n; };  // -1 .. 1, odd in i
  // tan(pi q / 4), exactly +-1 at the faces and odd in q.
  const auto tan4 = [](double q) { return q == 1.0 ? 1.0 : q == -1.0 ? -1.0 : std::tan(0.25 * std::numbers::pi * q); };
  const auto dir = [&](const Vec3& q) { return Vec3(tan4(q.x()), tan4(q.y()), tan4(q.z())).normalized(); };
  const auto bulged = [&](const Vec3& q) -> Vec3 { return a * ((1.0 - bulge) * q + bulge * sqrt3 * dir(q)); };

  // Node numbering: the core's lattice (i, j, k) first, i fastest; then layer by layer the
  // surface lattice points in the lattice's order.
  const auto core_id = [n1](int i, int j, int k) { return (k * n1 + j) * n1 + i; };
  const int core_nodes = n1 * n1 * n1;
  std::vector<int> surface(static_cast<std::size_t>(core_nodes), -1);
  int surface_nodes = 0;
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i)
        if (i == 0 || i == n || j == 0 || j == n || k == 0 || k == n)
          surface[static_cast<std::size_t>(core_id(i, j, k))] = surface_nodes++;
  // Node of lattice point (i, j, k) at layer l (0 = the core).
  const auto id = [&](int l, int i, int j, int k) {
    return l == 0 ? core_id(i, j, k) : core_nodes + (l - 1) * surface_nodes + surface[static_cast<std::size_t>(core_id(i, j, k))];
  };

  Mesh3 mesh;
  mesh.nodes.resize(3, core_nodes + nr * surface_nodes);
  const double r_mid = a * ((1.0 - bulge) + bulge * sqrt3);  // centre to the core's face centre
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const Vec3 xi(lattice(i), lattice(j), lattice(k));
        const double m = xi.cwiseAbs().maxCoeff();
        const Vec3 x = m == 0.0 ? Vec3::Zero() : Vec3(m * bulged(xi / m));
        mesh.nodes.col(core_id(i, j, k)) = x;
        if (m != 1.0) continue;
        const Vec3 outer = R * dir(xi);
        for (int l = 1; l <= nr; ++l) {
          const double t = std::expm1(std::log(R / r_mid) * l / nr) / (R / r_mid - 1.0);
          mesh.nodes.col(id(l, i, j, k)) = l == nr ? outer : Vec3(x + t * (outer - x));
        }
      }
  mesh.nodes.colwise() += spec.center;

  // Cells: the core's, then each face's block, layer by layer. A block cell's corners 0-3 are
  // its face cell at layer l - 1, 4-7 the same at layer l; the order is flipped where that
  // gives a negative volume (on the faces at the lattice's low side).
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        mesh.hexes.push_back({core_id(i, j, k), core_id(i + 1, j, k), core_id(i + 1, j + 1, k), core_id(i, j + 1, k),
                              core_id(i, j, k + 1), core_id(i + 1, j, k + 1), core_id(i + 1, j + 1, k + 1),
                              core_id(i, j + 1, k + 1)});
  for (int axis = 0; axis < 3; ++axis)
    for (const int side : {0, n}) {
      const int b = (axis + 1) % 3, c = (axis + 2) % 3;
      for (int v = 0; v < n; ++v)
        for (int u = 0; u < n; ++u) {
          const int du[4] = {0, 1, 1, 0}, dv[4] = {0, 0, 1, 1};
          std::array<std::array<int, 3>, 4> p{};
          for (int r = 0; r < 4; ++r) {
            p[static_cast<std::size_t>(r)][static_cast<std::size_t>(axis)] = side;
            p[static_cast<std::size_t>(r)][static_cast<std::size_t>(b)] = u + du[r];
            p[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)] = v + dv[r];
          }
          for (int l = 1; l <= nr; ++l) {
            std::array<int, 8> h{};
            for (int r = 0; r < 4; ++r) {
              const auto& pr = p[static_cast<std::size_t>(r)];
              h[static_cast<std::size_t>(r)] = id(l - 1, pr[0], pr[1], pr[2]);
              h[static_cast<std::size_t>(r + 4)] = id(l, pr[0], pr[1], pr[2]);
            }
            // (x1 - x0) x (x3 - x0) points along +axis: into the cell on the high side only.
            if (side == 0) h = {h[0], h[3], h[2], h[1], h[4], h[7], h[6], h[5]};
            mesh.hexes.push_back(h);
          }
        }
    }

  auto& sets = mesh.node_sets;
  std::vector<int>& boundary = sets["boundary"];
  for (int s = 0; s < surface_nodes; ++s) boundary.push_back(core_nodes + (nr - 1) * surface_nodes + s);
  set_all(mesh);
  if (n % 2 == 0) sets["center"] = {core_id(n / 2, n / 2, n / 2)};
  // The sphere's node(s) at the centre of each cube face.
  const char* extreme[3][2] = {{"leftmost", "rightmost"}, {"lowest", "highest"}, {"backmost", "frontmost"}};
  for (int axis = 0; axis < 3; ++axis)
    for (int s = 0; s < 2; ++s) {
      std::vector<int>& set = sets[extreme[axis][s]];
      const int b = (axis + 1) % 3, c = (axis + 2) % 3;
      const int lo = n / 2, hi = (n + 1) / 2;  // equal for n even
      for (const int u : {lo, hi})
        for (const int v : {lo, hi}) {
          std::array<int, 3> p{};
          p[static_cast<std::size_t>(axis)] = s * n;
          p[static_cast<std::size_t>(b)] = u;
          p[static_cast<std::size_t>(c)] = v;
          set.push_back(id(nr, p[0], p[1], p[2]));
        }
      sort_unique(set);
    }
  return mesh;
}

Mesh3 extrude(const Mesh& mesh, double thickness, int layers) {
  require_positive("extrude", "thickness", thickness);
  if (layers < 1) fail("extrude: layers must be >= 1 (got " + std::to_string(layers) + ")");
  if (mesh.num_cells() == 0) fail("extrude: the 2D mesh has no cells");
  if (!mesh.quads.empty() && !mesh.tris.empty())
    fail("extrude: the 2D mesh mixes quadrilaterals (" + std::to_string(mesh.quads.size()) + ") and triangles (" +
         std::to_string(mesh.tris.size()) +
         "); a hexahedron's side face cannot meet two tetrahedra's triangles: use one kind");
  const long long n2 = mesh.num_nodes();
  if (n2 * (layers + 1LL) > max_nodes)
    fail("extrude: nodes x (layers+1) must be <= " + std::to_string(max_nodes) + " nodes (got " +
         std::to_string(n2) + " nodes, layers " + std::to_string(layers) + ")");
  for (std::size_t c = 0; c < mesh.quads.size(); ++c)
    if (!(signed_area(mesh, mesh.quads[c].data(), 4) > 0.0))
      fail("extrude: 2D cell " + std::to_string(c) + " is not counter-clockwise (area <= 0)");
  for (std::size_t c = 0; c < mesh.tris.size(); ++c)
    if (!(signed_area(mesh, mesh.tris[c].data(), 3) > 0.0))
      fail("extrude: 2D cell " + std::to_string(mesh.quads.size() + c) + " is not counter-clockwise (area <= 0)");

  const int n = mesh.num_nodes();
  Mesh3 out;
  out.nodes.resize(3, n * (layers + 1));
  for (int l = 0; l <= layers; ++l) {
    // thickness (l/layers), as the box's coordinates: the front is exactly z = thickness.
    const double z = thickness * (static_cast<double>(l) / layers);
    for (int p = 0; p < n; ++p) out.nodes.col(l * n + p) = Vec3(mesh.nodes(0, p), mesh.nodes(1, p), z);
  }
  for (int l = 0; l < layers; ++l) {
    const int lo = l * n, hi = (l + 1) * n;
    for (const auto& q : mesh.quads)
      out.hexes.push_back({lo + q[0], lo + q[1], lo + q[2], lo + q[3], hi + q[0], hi + q[1], hi + q[2], hi + q[3]});
    for (const auto& t : mesh.tris) {
      std::array<int, 3> s = t;
      std::sort(s.begin(), s.end());
      // (a, b, c) = s is counter-clockwise if it is a rotation of t, i.e. b follows a in t.
      const int at = static_cast<int>(std::find(t.begin(), t.end(), s[0]) - t.begin());
      const bool ccw = t[static_cast<std::size_t>((at + 1) % 3)] == s[1];
      const int a = lo + s[0], b = lo + s[1], c = lo + s[2], a1 = hi + s[0], b1 = hi + s[1], c1 = hi + s[2];
      for (std::array<int, 4> tet : {std::array<int, 4>{a, b, c, c1}, std::array<int, 4>{a, b1, b, c1},
                                     std::array<int, 4>{a, a1, b1, c1}}) {
        if (!ccw) std::swap(tet[1], tet[2]);
        out.tets.push_back(tet);
      }
    }
  }

  for (const auto& [name, set] : mesh.node_sets) {
    std::vector<int>& extended = out.node_sets[name];
    extended.reserve(set.size() * static_cast<std::size_t>(layers + 1));
    for (int l = 0; l <= layers; ++l)
      for (const int p : set) extended.push_back(l * n + p);
    sort_unique(extended);  // already sorted when the 2D set is; a Gmsh set might not be unique
  }
  std::vector<int>& back = out.node_sets["back"];
  std::vector<int>& front = out.node_sets["front"];
  back.resize(static_cast<std::size_t>(n));
  front.resize(static_cast<std::size_t>(n));
  for (int p = 0; p < n; ++p) {
    back[static_cast<std::size_t>(p)] = p;
    front[static_cast<std::size_t>(p)] = layers * n + p;
  }
  out.node_sets["boundary"] = boundary_nodes(out);
  return out;
}

}  // namespace ricochet
