#include "harness/input/run_plan.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "harness/input/case_setup.hpp"
#include "harness/input/input_error.hpp"

namespace ricochet {
namespace {

constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;

std::string num(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.3g", x);
  return buf;
}

std::string gib(double bytes) { return num(bytes / kGiB) + " GiB"; }

// The rest of a message: which limit, and how to raise it.
std::string over_memory(const CaseSpec& c, double bytes) {
  return "about " + gib(bytes) + " of memory, more than limits.max_memory = " + num(c.limits.max_memory_gib) +
         " GiB (default: 80 % of this machine's " + gib(machine_memory_bytes()) + ")";
}

// Bytes one field snapshot holds until it is written: per node u, v, contact force (2 each),
// gap, status; per cell von Mises, Cauchy stress and Green-Lagrange strain (6 each).
double snapshot_bytes(double nodes, double cells) { return 8.0 * (7.0 * nodes + 13.0 * cells); }

// The history's columns: the summed ones, five per contact interface, four per probe (2D; six in 3D)
// (history_columns(), solver/schemes/run_monitor.hpp).
double history_columns(const CaseSpec& c) {
  const double d = c.dimension;  // 3D: momentum_z and three angular momentum columns, 6 per probe
  return 24.0 + 3.0 * (d - 2.0) + 5.0 * static_cast<double>(c.obstacles.size() + c.contact_pairs.size()) +
         2.0 * d * static_cast<double>(c.probes.size());
}

std::string where_of_body_cell(const PreparedCase& pc, int cell) {
  return with_model(pc, [&](const auto& model) {
    for (std::size_t b = 0; b < model.bodies.size(); ++b) {
      const auto& info = model.bodies[b];
      if (cell >= info.first_cell && cell < info.first_cell + info.num_cells)
        return "cell " + std::to_string(cell - info.first_cell) + " of " + pc.spec.bodies[b].where + " (\"" +
               info.name + "\")";
    }
    return "cell " + std::to_string(cell);
  });
}

}  // namespace

double machine_memory_bytes() {
  double bytes = 0.0;
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  if (pages > 0 && page > 0) bytes = static_cast<double>(pages) * static_cast<double>(page);
  // A container's or a Slurm job's cgroup can hold less than the machine ("max": no limit).
  std::ifstream cg("/sys/fs/cgroup/memory.max");
  std::string text;
  if (cg >> text && text != "max") {
    char* end = nullptr;
    const double limit = std::strtod(text.c_str(), &end);
    if (end && *end == '\0' && limit > 0.0 && (bytes == 0.0 || limit < bytes)) bytes = limit;
  }
  return bytes;
}

double default_max_memory_gib() {
  const double bytes = machine_memory_bytes();
  return bytes > 0.0 ? 0.8 * bytes / kGiB : 64.0;
}

double model_bytes(double nodes, double cells) {
  // Measured peak resident memory of `ricochet run` on rectangle meshes of 9e4, 3.6e5 and
  // 1e6 Q4 cells with no field snapshot: 132 MB, 357 MB, 1.35 GB (docs/reliability.md).
  // 1 kB per cell and 0.5 kB per node, plus 64 MiB for the program itself, bound them.
  return 1024.0 * cells + 512.0 * nodes + 64.0 * 1024.0 * 1024.0;
}

double generated_nodes2(const MeshSpec& m) {
  if (const auto* r = std::get_if<RectangleSpec>(&m.source)) return (r->nx + 1.0) * (r->ny + 1.0);
  if (const auto* a = std::get_if<ArcPlateSpec>(&m.source)) return (a->nx + 1.0) * (a->ny + 1.0);
  if (const auto* d = std::get_if<DiskSpec>(&m.source)) {
    const double n = d->n, nr = std::ceil(n / 2.0);
    return (n + 1.0) * (n + 1.0) + 4.0 * n * nr;
  }
  return -1.0;
}

double generated_cells2(const MeshSpec& m) {
  if (const auto* r = std::get_if<RectangleSpec>(&m.source)) return (r->triangles ? 2.0 : 1.0) * r->nx * double(r->ny);
  if (const auto* a = std::get_if<ArcPlateSpec>(&m.source)) return static_cast<double>(a->nx) * a->ny;
  if (const auto* d = std::get_if<DiskSpec>(&m.source)) {
    const double n = d->n, nr = std::ceil(n / 2.0);
    return n * n + 4.0 * n * nr;
  }
  return -1.0;
}

// 3D: the box's nodes and cells (6 tetrahedra a cell with cells = "tet"), the ball's, or an extrusion's: the
// 2D mesh's nodes at layers + 1 levels, its cells times the layers (3 tetrahedra a triangle's
// prism). -1 for a mesh file.
double generated_nodes(const MeshSpec& m) {
  if (const auto* b = std::get_if<BoxSpec>(&m.source)) return (b->nx + 1.0) * (b->ny + 1.0) * (b->nz + 1.0);
  if (const auto* b = std::get_if<BallSpec>(&m.source)) {
    const double n = b->n, nr = std::ceil(n / 2.0);
    return (n + 1.0) * (n + 1.0) * (n + 1.0) + nr * (6.0 * n * n + 2.0);
  }
  const double n2 = generated_nodes2(m);
  if (m.extrude && n2 >= 0.0) return n2 * (m.extrude->layers + 1.0);
  return n2;
}

double generated_cells(const MeshSpec& m) {
  if (const auto* b = std::get_if<BoxSpec>(&m.source)) return (b->tetrahedra ? 6.0 : 1.0) * b->nx * double(b->ny) * b->nz;
  if (const auto* b = std::get_if<BallSpec>(&m.source)) {
    const double n = b->n, nr = std::ceil(n / 2.0);
    return n * n * n + 6.0 * n * n * nr;
  }
  const double e2 = generated_cells2(m);
  if (m.extrude && e2 >= 0.0) {
    const auto* r = std::get_if<RectangleSpec>(&m.source);
    const auto* a = std::get_if<ArcPlateSpec>(&m.source);
    const bool tris = (r && r->triangles) || (a && a->triangles);
    return e2 * m.extrude->layers * (tris ? 3.0 : 1.0);
  }
  return e2;
}

void check_mesh_plan(const CaseSpec& c) {
  double nodes = 0.0, cells = 0.0;
  std::string largest;
  double largest_cells = 0.0;
  for (const BodySpec& b : c.bodies) {
    const auto it = c.meshes.find(b.mesh);
    if (it == c.meshes.end()) continue;
    const double n = generated_nodes(it->second), e = generated_cells(it->second);
    if (e < 0.0) continue;  // a Gmsh file: its size is its own bound
    nodes += n;
    cells += e;
    if (e > largest_cells) largest_cells = e, largest = it->second.where;
  }
  const double bytes = model_bytes(nodes, cells);
  if (bytes > c.limits.max_memory_gib * kGiB)
    throw InputError(c.file + ": " + largest + ": the generated meshes have " + num(cells) + " cells and " + num(nodes) +
                     " nodes, " + over_memory(c, bytes) + "; use fewer cells (nx, ny, nz, n, extrude.layers) or raise limits.max_memory");
}

double planned_history_rows(double steps, double dt, double interval) {
  if (!(interval > dt)) return steps + 1.0;  // every step (an interval up to one step samples each)
  return std::min(steps + 1.0, std::floor(steps * dt / interval) + 2.0);
}

void check_run_plan(const PreparedCase& pc) {
  const CaseSpec& c = pc.spec;
  const RunSettings& s = pc.settings;
  const double dt = s.dt;
  const int cell = with_model(pc, [](const auto& m) { return m.critical_cell; });
  const std::string by = cell >= 0 ? ", set by " + where_of_body_cell(pc, cell) : "";
  const std::string dt_text =
      pc.dt_auto() ? "time.dt = \"auto\" (" + num(dt) + " s" + by + ")" : "time.dt = " + num(dt) + " s";
  if (pc.dt_auto()) {
    const std::string from = cell >= 0 ? "; the critical step of " + where_of_body_cell(pc, cell) : "";
    if (!(dt > 0.0) || !std::isfinite(dt))
      throw InputError(c.file + ": time.dt: \"auto\" gives " + num(dt) + " s, not a positive finite step" + from +
                       " (cell length / wave speed) overflows or vanishes: check that body's material (moduli, "
                       "density) and its mesh's size");
    if (dt > c.end_time)
      throw InputError(c.file + ": time.dt: \"auto\" gives " + num(dt) + " s (time.safety x the critical step" + from +
                       "), more than time.end = " + num(c.end_time) +
                       " s: the run would not take one step; a longer time.end or a fixed time.dt <= time.end");
  }
  const double steps = std::ceil(c.end_time / dt - 1e-9);
  if (!(steps <= c.limits.max_steps))
    throw InputError(c.file + ": time.end = " + num(c.end_time) + " s at " + dt_text + " is " + num(steps) +
                     " steps, more than limits.max_steps = " + num(c.limits.max_steps) +
                     "; a shorter time.end, a longer time.dt, or raise limits.max_steps");
  const double rows = planned_history_rows(steps, dt, s.sample_interval);
  if (!(rows <= c.limits.max_history_rows))
    throw InputError(c.file + ": output.interval = " + num(s.sample_interval) + " s over time.end = " + num(c.end_time) +
                     " s at " + dt_text + " gives " + num(rows) + " history rows, more than limits.max_history_rows = " +
                     num(c.limits.max_history_rows) + "; a longer output.interval, or raise limits.max_history_rows");
  const double nodes = with_model(pc, [](const auto& m) { return m.num_nodes(); });
  const double cells = with_model(pc, [](const auto& m) { return m.num_cells(); });
  double snapshots = 1.0;  // a diverged run's last state
  for (double t : s.field_times)
    if (t <= c.end_time * (1.0 + 1e-9)) snapshots += 1.0;
  const double history = 8.0 * rows * history_columns(c);
  const double fields = snapshots * snapshot_bytes(nodes, cells);
  const double bytes = model_bytes(nodes, cells) + history + fields;
  if (bytes > c.limits.max_memory_gib * kGiB)
    throw InputError(c.file + ": the run holds " + num(cells) + " cells, " + num(rows) + " history rows and " +
                     num(snapshots) + " field snapshots until it writes them, " + over_memory(c, bytes) +
                     "; fewer cells, a longer output.interval, fewer output.fields, or raise limits.max_memory");
}

}  // namespace ricochet
