#include "harness/input/mesh_generators.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include "harness/input/generator_checks.hpp"
#include "harness/input/input_error.hpp"

namespace ricochet {
namespace {

using generator_checks::fail;
using generator_checks::max_nodes;
using generator_checks::require_positive;
using generator_checks::str;

void require_cells(const char* gen, int nx, int ny) {
  if (nx < 1) fail(std::string(gen) + ": nx must be >= 1 (got " + std::to_string(nx) + ")");
  if (ny < 1) fail(std::string(gen) + ": ny must be >= 1 (got " + std::to_string(ny) + ")");
  const long long nodes = (static_cast<long long>(nx) + 1) * (static_cast<long long>(ny) + 1);
  if (nodes > max_nodes)
    fail(std::string(gen) + ": (nx+1)*(ny+1) must be <= " + std::to_string(max_nodes) +
         " nodes (got nx " + std::to_string(nx) + ", ny " + std::to_string(ny) + ")");
}

// Cells and node sets of a structured grid of (nx+1) x (ny+1) nodes, node (i, j) at index
// j*(nx+1) + i, whose coordinates the caller has filled in. Cells are counter-clockwise if
// x grows with i and y grows with j.
void fill_grid_topology(Mesh& mesh, int nx, int ny, bool triangles) {
  const auto id = [nx](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const int a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      if (!triangles) {
        mesh.quads.push_back({a, b, c, d});
      } else if (i % 2 == 0) {  // diagonal a-c
        mesh.tris.push_back({a, b, c});
        mesh.tris.push_back({a, c, d});
      } else {  // diagonal b-d
        mesh.tris.push_back({a, b, d});
        mesh.tris.push_back({b, c, d});
      }
    }
  }
  auto& sets = mesh.node_sets;
  for (int i = 0; i <= nx; ++i) {
    sets["bottom"].push_back(id(i, 0));
    sets["top"].push_back(id(i, ny));
  }
  for (int j = 0; j <= ny; ++j) {
    sets["left"].push_back(id(0, j));
    sets["right"].push_back(id(nx, j));
  }
  std::vector<int>& boundary = sets["boundary"];
  for (const char* side : {"bottom", "top", "left", "right"})
    boundary.insert(boundary.end(), sets[side].begin(), sets[side].end());
  std::sort(boundary.begin(), boundary.end());
  boundary.erase(std::unique(boundary.begin(), boundary.end()), boundary.end());
  std::vector<int>& all = sets["all"];
  all.resize(static_cast<std::size_t>(mesh.num_nodes()));
  for (int k = 0; k < mesh.num_nodes(); ++k) all[static_cast<std::size_t>(k)] = k;
}

// A vector given in the frame of the right-hand quarter of a disk, turned by b x 90 degrees
// counter-clockwise with exact coordinate swaps (no rounding, so the quarters are exact
// images of each other).
Vec2 quarter_turn(int b, double x, double y) {
  switch (b) {
    case 0: return {x, y};
    case 1: return {-y, x};
    case 2: return {-x, -y};
    default: return {y, -x};
  }
}

}  // namespace

Mesh make_rectangle(const RectangleSpec& spec) {
  const char* gen = "rectangle";
  require_positive(gen, "width", spec.width);
  require_positive(gen, "height", spec.height);
  require_cells(gen, spec.nx, spec.ny);
  if (!spec.origin.allFinite())
    fail("rectangle: origin must be finite (got " + str(spec.origin.x()) + ", " +
         str(spec.origin.y()) + ")");

  Mesh mesh;
  const int nx = spec.nx, ny = spec.ny;
  mesh.nodes.resize(2, (nx + 1) * (ny + 1));
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      const int k = j * (nx + 1) + i;
      mesh.nodes(0, k) = spec.origin.x() + spec.width * (static_cast<double>(i) / nx);
      mesh.nodes(1, k) = spec.origin.y() + spec.height * (static_cast<double>(j) / ny);
    }
  }
  fill_grid_topology(mesh, nx, ny, spec.triangles);
  return mesh;
}

Mesh make_arc_plate(const ArcPlateSpec& spec) {
  const char* gen = "arc_plate";
  require_positive(gen, "width", spec.width);
  require_positive(gen, "height", spec.height);
  require_positive(gen, "radius", spec.radius);
  require_cells(gen, spec.nx, spec.ny);
  if (!std::isfinite(spec.bias) || spec.bias <= 0.0)
    fail("arc_plate: bias must be finite and > 0 (got " + str(spec.bias) + ")");
  const double L = spec.width, R = spec.radius;
  if (!(R > 0.5 * L))
    fail("arc_plate: radius must be > width/2 (got " + str(R) + ", width " + str(L) + ")");

  const auto arc_y = [R](double x) { return R - std::sqrt(R * R - x * x); };
  const double sagitta = arc_y(0.5 * L);
  const double y_top = spec.height_is_overall ? spec.height : sagitta + spec.height;
  if (spec.height_is_overall && !(y_top > sagitta))
    fail("arc_plate: height must be > the arc's sagitta " + str(sagitta) +
         " when height_is_overall (got " + str(spec.height) + ")");

  // Row fractions t_j in [0, 1]: geometric with ratio r per row, r^(ny-1) = bias.
  const int nx = spec.nx, ny = spec.ny;
  const double log_r = ny > 1 ? std::log(spec.bias) / (ny - 1) : 0.0;
  std::vector<double> t(static_cast<std::size_t>(ny) + 1);
  for (int j = 0; j <= ny; ++j) {
    t[static_cast<std::size_t>(j)] =
        log_r == 0.0 ? static_cast<double>(j) / ny : std::expm1(j * log_r) / std::expm1(ny * log_r);
  }
  t.front() = 0.0;
  t.back() = 1.0;

  Mesh mesh;
  mesh.nodes.resize(2, (nx + 1) * (ny + 1));
  for (int i = 0; i <= nx; ++i) {
    // x_i = -L/2 + i*L/nx, written so that the corners are exactly +-L/2 and columns i and
    // nx - i are exact mirror images.
    const double x = 0.5 * L * (static_cast<double>(2 * i - nx) / nx);
    const double y_bottom = arc_y(x);
    for (int j = 0; j <= ny; ++j) {
      const int k = j * (nx + 1) + i;
      mesh.nodes(0, k) = x;
      mesh.nodes(1, k) =
          j == ny ? y_top : y_bottom + (y_top - y_bottom) * t[static_cast<std::size_t>(j)];
    }
  }
  fill_grid_topology(mesh, nx, ny, spec.triangles);
  mesh.node_sets["top_left"] = {ny * (nx + 1)};
  mesh.node_sets["top_right"] = {ny * (nx + 1) + nx};
  if (nx % 2 == 0)
    mesh.node_sets["lowest"] = {nx / 2};
  else
    mesh.node_sets["lowest"] = {nx / 2, nx / 2 + 1};
  return mesh;
}

Mesh make_disk(const DiskSpec& spec) {
  require_positive("disk", "radius", spec.radius);
  if (!spec.center.allFinite())
    fail("disk: center must be finite (got " + str(spec.center.x()) + ", " + str(spec.center.y()) +
         ")");
  if (spec.n < 1) fail("disk: n must be >= 1 (got " + std::to_string(spec.n) + ")");
  const long long n_ll = spec.n, nr_ll = (n_ll + 1) / 2;
  if ((n_ll + 1) * (n_ll + 1) + 4 * n_ll * nr_ll > max_nodes)
    fail("disk: (n+1)^2 + 4 n ceil(n/2) must be <= " + std::to_string(max_nodes) +
         " nodes (got n " + std::to_string(spec.n) + ")");

  // Central block: half-width a = 0.4 R, sides bulged by 0.3 towards the circle of radius
  // a sqrt(2) through its corners (docs in the header: these give cell angles of about
  // 61-125 degrees and near-square ring cells with nr = ceil(n/2)).
  constexpr double core = 0.4, bulge = 0.3;
  const int n = spec.n, nr = (n + 1) / 2, ring = 4 * n;
  const double R = spec.radius, a = core * R, a_corner = a * std::numbers::sqrt2;
  const double r_mid = (1.0 - bulge) * a + bulge * a_corner;  // centre to a side's midpoint
  const int block_nodes = (n + 1) * (n + 1);
  const auto block_id = [n](int i, int j) { return j * (n + 1) + i; };
  const auto ring_id = [&](int k, int p) { return block_nodes + (k - 1) * ring + p % ring; };

  // The block's boundary nodes and the rim, by perimeter position p = b n + j (quarter b,
  // j = 0 .. n-1), counter-clockwise from the block corner at angle -pi/4.
  Mesh mesh;
  mesh.nodes.resize(2, block_nodes + nr * ring);
  std::vector<int> side(static_cast<std::size_t>(ring));
  std::vector<Vec2> rim(static_cast<std::size_t>(ring));
  for (int b = 0; b < 4; ++b) {
    for (int j = 0; j < n; ++j) {
      const int p = b * n + j;
      const double s = static_cast<double>(2 * j - n) / n;  // -1 .. 1 along the side; odd in j
      const double phi = 0.25 * std::numbers::pi * s;
      const double c = std::cos(phi), sn = std::sin(phi);
      const int id = b == 0 ? block_id(n, j) : b == 1 ? block_id(n - j, n)
                   : b == 2 ? block_id(0, n - j) : block_id(j, 0);
      side[static_cast<std::size_t>(p)] = id;
      mesh.nodes.col(id) = quarter_turn(b, (1.0 - bulge) * a + bulge * a_corner * c,
                                        (1.0 - bulge) * a * s + bulge * a_corner * sn);
      rim[static_cast<std::size_t>(p)] = quarter_turn(b, R * c, R * sn);
    }
  }
  // Block interior: transfinite (Coons) interpolation of the four sides.
  const auto X = [&](int i, int j) -> Vec2 { return mesh.nodes.col(block_id(i, j)); };
  for (int j = 1; j < n; ++j) {
    for (int i = 1; i < n; ++i) {
      const double u = static_cast<double>(i) / n, v = static_cast<double>(j) / n;
      mesh.nodes.col(block_id(i, j)) =
          (1 - u) * X(0, j) + u * X(n, j) + (1 - v) * X(i, 0) + v * X(i, n) -
          ((1 - u) * (1 - v) * X(0, 0) + u * (1 - v) * X(n, 0) + (1 - u) * v * X(0, n) + u * v * X(n, n));
    }
  }
  // Rings: geometric spacing with the growth of a log-polar grid from r_mid to R.
  for (int k = 1; k <= nr; ++k) {
    const double t = k == nr ? 1.0 : std::expm1(std::log(R / r_mid) * k / nr) / (R / r_mid - 1.0);
    for (int p = 0; p < ring; ++p) {
      const Vec2 inner = mesh.nodes.col(side[static_cast<std::size_t>(p)]);
      const Vec2& outer = rim[static_cast<std::size_t>(p)];
      mesh.nodes.col(ring_id(k, p)) = k == nr ? outer : Vec2(inner + t * (outer - inner));
    }
  }
  mesh.nodes.colwise() += spec.center;

  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      mesh.quads.push_back({block_id(i, j), block_id(i + 1, j), block_id(i + 1, j + 1), block_id(i, j + 1)});
  const auto node = [&](int k, int p) {
    return k == 0 ? side[static_cast<std::size_t>(p % ring)] : ring_id(k, p);
  };
  for (int k = 1; k <= nr; ++k)
    for (int p = 0; p < ring; ++p)  // inner p, outer p, outer p+1, inner p+1: counter-clockwise
      mesh.quads.push_back({node(k - 1, p), node(k, p), node(k, p + 1), node(k - 1, p + 1)});

  auto& sets = mesh.node_sets;
  std::vector<int>& boundary = sets["boundary"];
  for (int p = 0; p < ring; ++p) boundary.push_back(ring_id(nr, p));
  std::vector<int>& all = sets["all"];
  all.resize(static_cast<std::size_t>(mesh.num_nodes()));
  for (int k = 0; k < mesh.num_nodes(); ++k) all[static_cast<std::size_t>(k)] = k;
  if (n % 2 == 0) sets["center"] = {block_id(n / 2, n / 2)};
  // The rim node(s) at the middle of quarter b: angle b x 90 degrees.
  const char* extreme[4] = {"rightmost", "highest", "leftmost", "lowest"};
  for (int b = 0; b < 4; ++b) {
    std::vector<int>& set = sets[extreme[b]];
    if (n % 2 == 0)
      set = {ring_id(nr, b * n + n / 2)};
    else
      set = {ring_id(nr, b * n + n / 2), ring_id(nr, b * n + n / 2 + 1)};
    std::sort(set.begin(), set.end());
  }
  return mesh;
}

std::vector<double> local_element_size(const Mesh& mesh) {
  std::vector<double> h2(mesh.num_nodes(), std::numeric_limits<double>::infinity());
  auto edge = [&](int a, int b) {
    const double dx = mesh.nodes(0, b) - mesh.nodes(0, a), dy = mesh.nodes(1, b) - mesh.nodes(1, a);
    const double l2 = std::fma(dx, dx, dy * dy);
    h2[a] = std::min(h2[a], l2);
    h2[b] = std::min(h2[b], l2);
  };
  for (const auto& q : mesh.quads)
    for (int k = 0; k < 4; ++k) edge(q[k], q[(k + 1) % 4]);
  for (const auto& t : mesh.tris)
    for (int k = 0; k < 3; ++k) edge(t[k], t[(k + 1) % 3]);
  for (double& v : h2) v = std::sqrt(v);  // sqrt(inf) = inf
  return h2;
}

void distort_mesh(Mesh& mesh, double distort, std::uint64_t seed) {
  if (!(std::isfinite(distort) && distort >= 0.0)) fail("distort must be finite and >= 0 (got " + str(distort) + ")");
  if (distort == 0.0) return;
  const std::vector<double> h = local_element_size(mesh);
  std::vector<char> on_boundary(mesh.num_nodes(), 0);
  for (int n : boundary_nodes(mesh)) on_boundary[n] = 1;
  std::mt19937_64 random(seed);
  // A draw as a double r uniform in [-1, 1): the top 53 bits k as u = k 2^-53, then 2u - 1.
  auto draw = [&random] {
    const double u = static_cast<double>(random() >> 11) * 0x1p-53;
    return 2.0 * u - 1.0;
  };
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    if (on_boundary[i] || !std::isfinite(h[i])) continue;
    const double amplitude = distort * h[i];
    const double rx = draw();
    const double ry = draw();
    mesh.nodes(0, i) = std::fma(amplitude, rx, mesh.nodes(0, i));
    mesh.nodes(1, i) = std::fma(amplitude, ry, mesh.nodes(1, i));
  }
  auto nodes_of = [](const int* c, int count) {
    std::string s;
    for (int k = 0; k < count; ++k) {
      if (k > 0) s += ' ';
      s += std::to_string(c[k]);
    }
    return s;
  };
  const std::string advice = "; lower distort (got " + str(distort) + ") or use another seed";
  for (std::size_t c = 0; c < mesh.quads.size(); ++c) {
    const auto& q = mesh.quads[c];
    if (!(signed_area(mesh, q.data(), 4) > 0.0))
      fail("after distortion Q4 cell " + std::to_string(c) + " (nodes " + nodes_of(q.data(), 4) +
           ") has no positive area" + advice);
    if (!(q4_corner_quality(mesh, q) > 0.0))
      fail("after distortion Q4 cell " + std::to_string(c) + " (nodes " + nodes_of(q.data(), 4) +
           ") is not convex (a corner Jacobian is <= 0)" + advice);
  }
  for (std::size_t c = 0; c < mesh.tris.size(); ++c) {
    const auto& t = mesh.tris[c];
    if (!(signed_area(mesh, t.data(), 3) > 0.0))
      fail("after distortion T3 cell " + std::to_string(mesh.quads.size() + c) + " (nodes " +
           nodes_of(t.data(), 3) + ") has no positive area" + advice);
  }
}

}  // namespace ricochet
