#include "harness/mesh_generators.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "harness/input_error.hpp"

namespace ricochet {
namespace {

// Largest node count a generator builds; keeps indices in int and memory bounded.
constexpr long long max_nodes = 100'000'000;

[[noreturn]] void fail(const std::string& message) {
  throw InputError(message);
}

std::string str(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

void require_positive(const char* gen, const char* name, double v) {
  if (!std::isfinite(v) || v <= 0.0)
    fail(std::string(gen) + ": " + name + " must be finite and > 0 (got " + str(v) + ")");
}

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
  fill_grid_topology(mesh, nx, ny, false);
  mesh.node_sets["top_left"] = {ny * (nx + 1)};
  mesh.node_sets["top_right"] = {ny * (nx + 1) + nx};
  if (nx % 2 == 0)
    mesh.node_sets["lowest"] = {nx / 2};
  else
    mesh.node_sets["lowest"] = {nx / 2, nx / 2 + 1};
  return mesh;
}

}  // namespace ricochet
