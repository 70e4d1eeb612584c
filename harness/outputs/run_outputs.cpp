#include "harness/outputs/run_outputs.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <stdexcept>
#include <system_error>

#include "harness/outputs/atomic_file.hpp"
#include "harness/outputs/csv_writer.hpp"
#include "harness/outputs/vtu_writer.hpp"

namespace ricochet {
namespace {


// The arrays of a snapshot (docs/outputs.md, fields/*.vtu), 2D (VtuData) or 3D (VtuData3):
// the nodes' vectors u, v and contact force, and the per-cell values in the file's cell order.
template <class Data, class Map>
void set_arrays(Data& d, const FieldSnapshot& f, const Map& u, const Map& v, const Map& force, std::vector<double> vm,
                std::vector<double> cauchy, std::vector<double> green_lagrange, std::vector<int> body_id) {
  using Vectors = typename Map::PlainObject;
  d.point_vectors = {{"displacement", Vectors(u)}, {"velocity", Vectors(v)}, {"contact_force", Vectors(force)}};
  d.point_scalars = {{"contact_gap", f.contact_gap}};
  d.point_ints = {{"contact_status", f.contact_status}};
  d.cell_scalars = {{"von_mises", std::move(vm)}};
  d.cell_tensors = {{"cauchy_stress", std::move(cauchy)}, {"green_lagrange_strain", std::move(green_lagrange)}};
  d.cell_ints = {{"body", std::move(body_id)}};
}

std::string format_vtu_snapshot(const PreparedCase& pc, const FieldSnapshot& f) {
  const Model<2>& m = pc.model<2>();
  const std::vector<Mesh>& meshes = pc.meshes<2>();
  VtuData d;
  d.time = f.time;
  const Eigen::Map<const Eigen::Matrix2Xd> u(f.u.data(), 2, m.num_nodes());
  const Eigen::Map<const Eigen::Matrix2Xd> v(f.v.data(), 2, m.num_nodes());
  d.points = m.ref + u;
  std::vector<int> body(m.num_cells());
  // Cells in global order: per body its quads, then its triangles (as the model numbers them).
  for (std::size_t b = 0; b < meshes.size(); ++b) {
    const int n0 = m.bodies[b].first_node;
    for (auto q : meshes[b].quads) {
      for (int& i : q) i += n0;
      d.quads.push_back(q);
    }
  }
  for (std::size_t b = 0; b < meshes.size(); ++b) {
    const int n0 = m.bodies[b].first_node;
    for (auto t : meshes[b].tris) {
      for (int& i : t) i += n0;
      d.tris.push_back(t);
    }
  }
  // VTU order is all quads then all triangles; map the per-cell values to it.
  std::vector<double> vm, cauchy, green_lagrange;
  std::vector<int> body_id;
  vm.reserve(m.num_cells());
  cauchy.reserve(6 * static_cast<std::size_t>(m.num_cells()));
  green_lagrange.reserve(cauchy.capacity());
  for (int pass = 0; pass < 2; ++pass)
    for (std::size_t b = 0; b < meshes.size(); ++b) {
      const int c0 = m.bodies[b].first_cell;
      const int nq = static_cast<int>(meshes[b].quads.size());
      const int begin = pass == 0 ? c0 : c0 + nq;
      const int end = pass == 0 ? c0 + nq : c0 + m.bodies[b].num_cells;
      for (int c = begin; c < end; ++c) {
        vm.push_back(f.von_mises[c]);
        cauchy.insert(cauchy.end(), f.cauchy.begin() + 6 * c, f.cauchy.begin() + 6 * c + 6);
        green_lagrange.insert(green_lagrange.end(), f.green_lagrange.begin() + 6 * c,
                              f.green_lagrange.begin() + 6 * c + 6);
        body_id.push_back(static_cast<int>(b));
      }
    }
  if (f.contact_force.size() != 2 * static_cast<std::size_t>(m.num_nodes()) ||
      f.cauchy.size() != 6 * static_cast<std::size_t>(m.num_cells()) || f.green_lagrange.size() != f.cauchy.size())
    throw std::logic_error("field snapshot of step " + std::to_string(f.step) + " lacks its tensors or contact data");
  const Eigen::Map<const Eigen::Matrix2Xd> force(f.contact_force.data(), 2, m.num_nodes());
  set_arrays(d, f, u, v, force, std::move(vm), std::move(cauchy), std::move(green_lagrange), std::move(body_id));
  return format_vtu(d, pc.spec.field_format);
}

// 3D: the hexahedra and tetrahedra of every body in global cell order (per body its hexahedra,
// then its tetrahedra, as the model numbers them and VtuData3 writes them: VTU's order is the
// cells', hexes then tets per body, so the per-cell values need no reordering).
std::string format_vtu_snapshot3(const PreparedCase& pc, const FieldSnapshot& f) {
  const Model<3>& m = pc.model<3>();
  const std::vector<Mesh3>& meshes = pc.meshes<3>();
  const int n = m.num_nodes();
  if (f.contact_force.size() != 3 * static_cast<std::size_t>(n) ||
      f.cauchy.size() != 6 * static_cast<std::size_t>(m.num_cells()) || f.green_lagrange.size() != f.cauchy.size())
    throw std::logic_error("field snapshot of step " + std::to_string(f.step) + " lacks its tensors or contact data");
  VtuData3 d;
  d.time = f.time;
  const Eigen::Map<const Eigen::Matrix3Xd> u(f.u.data(), 3, n), v(f.v.data(), 3, n), force(f.contact_force.data(), 3, n);
  d.points = m.ref + u;
  // VtuData3 writes all hexahedra, then all tetrahedra: with several bodies the cells' values
  // are put in that order.
  std::vector<int> order;  // global cell of each VTU cell
  for (int pass = 0; pass < 2; ++pass)
    for (std::size_t b = 0; b < meshes.size(); ++b) {
      const int n0 = m.bodies[b].first_node, c0 = m.bodies[b].first_cell;
      const Mesh3& mesh = meshes[b];
      const int nh = static_cast<int>(mesh.hexes.size());
      if (pass == 0) {
        for (int k = 0; k < nh; ++k) {
          auto h = mesh.hexes[k];
          for (int& i : h) i += n0;
          d.hexes.push_back(h);
          order.push_back(c0 + k);
        }
      } else {
        for (int k = 0; k < static_cast<int>(mesh.tets.size()); ++k) {
          auto t = mesh.tets[k];
          for (int& i : t) i += n0;
          d.tets.push_back(t);
          order.push_back(c0 + nh + k);
        }
      }
    }
  std::vector<double> vm, cauchy, green_lagrange;
  std::vector<int> body_id;
  for (int c : order) {
    vm.push_back(f.von_mises[c]);
    cauchy.insert(cauchy.end(), f.cauchy.begin() + 6 * c, f.cauchy.begin() + 6 * c + 6);
    green_lagrange.insert(green_lagrange.end(), f.green_lagrange.begin() + 6 * c, f.green_lagrange.begin() + 6 * c + 6);
    int b = 0;
    while (b + 1 < static_cast<int>(m.bodies.size()) && m.bodies[b + 1].first_cell <= c) ++b;
    body_id.push_back(b);
  }
  set_arrays(d, f, u, v, force, std::move(vm), std::move(cauchy), std::move(green_lagrange), std::move(body_id));
  return format_vtu(d, pc.spec.field_format);
}

}  // namespace

const char* plane_name(PlaneMode p) { return p == PlaneMode::stress ? "stress" : "strain"; }

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

Json build_info() {
  Json build = Json::object();
  build["compiler"] = __VERSION__;
#ifdef NDEBUG
  build["build_type"] = "release";
#else
  build["build_type"] = "debug";
#endif
  return build;
}

std::string joined_bodies(const CaseSpec& c, bool element) {
  std::string s;
  for (const auto& b : c.bodies) s += (s.empty() ? "" : "+") + (element ? b.element : b.mesh);
  return s;
}

Json case_identity(const PreparedCase& pc) {
  const CaseSpec& c = pc.spec;
  Json j = Json::object();
  j["ricochet_version"] = RICOCHET_VERSION;
  j["case"] = c.name;
  j["case_file"] = c.file;
  Json overrides = Json::array();
  for (const auto& o : c.overrides) overrides.push_back(o);
  j["overrides"] = overrides;
  j["scheme"] = scheme_name(c.scheme);
  j["mesh"] = joined_bodies(c, false);
  j["element"] = joined_bodies(c, true);
  return j;
}

void add_case_shape(Json& j, const PreparedCase& pc) {
  const CaseSpec& c = pc.spec;
  j["dimension"] = c.dimension;
  j["plane"] = c.dimension == 2 ? Json(plane_name(c.plane)) : Json();
  // The friction coefficient of the first body-obstacle pair (null without obstacles).
  if (pc.settings.friction.empty() || pc.settings.friction.front().empty())
    j["friction_coeff"] = nullptr;
  else
    j["friction_coeff"] = pc.settings.friction.front().front();
  j["obstacles"] = static_cast<long>(c.obstacles.size());
  j["contact_pairs"] = static_cast<long>(pc.settings.body_pairs.size());
}

void add_model_size(Json& j, const PreparedCase& pc) {
  with_model(pc, [&](const auto& m) {
    j["nodes"] = m.num_nodes();
    j["elements"] = m.num_cells();
  });
}

Json probes_json(const PreparedCase& pc) {
  Json probes = Json::array();
  for (const auto& p : pc.probes) {
    Json q = Json::object();
    q["name"] = p.name;
    q["body"] = p.body;
    q["node"] = p.node;
    q["x"] = p.position.x();
    q["y"] = p.position.y();
    if (pc.dimension() == 3) q["z"] = p.position.z();
    q["distance"] = p.distance;
    probes.push_back(q);
  }
  return probes;
}

Json run_summary(const PreparedCase& pc, const RunResult& r) {
  const CaseSpec& c = pc.spec;
  Json j = case_identity(pc);
  add_case_shape(j, pc);
  const bool any_contact = !c.obstacles.empty() || !pc.settings.body_pairs.empty();
  j["contact_level"] = !any_contact || pc.spec.scheme == Scheme::explicit_penalty ? Json()
                       : Json(pc.settings.contact.level == ContactLevel::position ? "position" : "velocity");
  // Only where it acts (the semi-explicit scheme at position level, the implicit scheme), and
  // only when asked for: runs with the paper's frozen frame keep the summary they had.
  if (any_contact && pc.settings.contact.frame_updates > 0 &&
      ((pc.spec.scheme == Scheme::semi_explicit && pc.settings.contact.level == ContactLevel::position) ||
       pc.spec.scheme == Scheme::implicit))
    j["contact_frame_updates"] = pc.settings.contact.frame_updates;
  add_model_size(j, pc);
  j["dt"] = r.dt;
  j["dt_mode"] = pc.dt_auto() ? "auto" : "fixed";
  j["dt_safety"] = pc.dt_auto() ? Json(c.dt_safety) : Json();
  // The variable step (docs/outputs.md): the steps' range, the last step shortened to end on
  // time.end aside; both dt for a fixed step.
  j["dt_update_interval"] = r.dt_update_interval;
  j["dt_min"] = r.dt_min;
  j["dt_max"] = r.dt_max;
  j["dt_updates"] = r.dt_updates;
  j["dt_floor"] = r.dt_update_interval > 0 ? Json(r.dt_floor) : Json();
  j["critical_dt"] = with_model(pc, [](const auto& m) { return m.critical_dt; });
  j["penalty_critical_dt"] = pc.penalty_critical_dt > 0.0 ? Json(pc.penalty_critical_dt) : Json();
  j["end_time"] = c.end_time;
  j["time_reached"] = r.end_time;
  j["steps"] = r.steps;
  j["planned_steps"] = r.planned_steps;
  j["status"] = r.status == RunStatus::ok ? "ok" : "diverged";
  if (r.status == RunStatus::diverged) {
    Json d = Json::object();
    d["reason"] = r.reason;
    d["step"] = r.diverged_step;
    d["time"] = r.diverged_time;
    j["diverged"] = d;
  } else {
    j["diverged"] = nullptr;
  }
  // The quasi-static start (docs/outputs.md), null without one.
  if (r.relaxed) {
    const RelaxationReport& x = r.relaxation;
    Json rx = Json::object();
    rx["converged"] = x.converged;
    rx["steps"] = x.steps;
    rx["velocity_resets"] = x.velocity_resets;
    rx["dt"] = x.dt;
    rx["tolerance"] = pc.settings.relaxation.tolerance;
    rx["residual"] = x.residual;
    rx["kinetic_ratio"] = x.kinetic_ratio;
    rx["settlement"] = x.settlement;
    rx["wall_seconds"] = x.wall_seconds;
    j["relaxation"] = rx;
  } else {
    j["relaxation"] = nullptr;
  }
  if (pc.spec.scheme == Scheme::implicit) {
    Json im = Json::object();
    im["theta"] = pc.spec.implicit.theta;
    im["xi"] = pc.spec.implicit.xi;
    im["newton_iterations"] = r.implicit.newton_iterations;
    im["newton_iterations_per_step"] = r.steps > 0 ? static_cast<double>(r.implicit.newton_iterations) / r.steps : 0.0;
    im["linear_iterations"] = r.implicit.linear_iterations;
    im["linear_solver"] = r.implicit.mass_solver ? (r.implicit.direct_solver ? "mass+direct" : "mass")
                          : r.implicit.direct_solver ? "direct"
                                                     : "pcg";
    if (r.implicit.direct_solver) {
      im["factor_method"] = r.implicit.supernodal ? "supernodal" : "simplicial";
      im["solve_precision"] = r.implicit.single_solves ? "single" : "double";
    }
    im["mass_iterations"] = r.implicit.mass_iterations;
    im["factorizations"] = r.implicit.factorizations;
    im["refactor_iterations"] = r.implicit.refactor_iterations;
    im["phase_seconds"] = Json{{"assembly", r.implicit.assembly_seconds},
                               {"factorization", r.implicit.factorization_seconds},
                               {"solve", r.implicit.solve_seconds},
                               {"contact", r.implicit.contact_seconds},
                               {"residual", r.implicit.residual_seconds}};
    j["implicit"] = im;
  } else {
    j["implicit"] = nullptr;
  }
  if (pc.spec.scheme == Scheme::explicit_penalty) {
    j["penalty_scale_factor"] = pc.spec.penalty.scale_factor;
    j["penalty_soft_scale"] = pc.settings.penalty.soft_scale;
    j["penalty_soft_dt"] = pc.settings.penalty.soft_scale > 0.0 ? Json(pc.settings.penalty.soft_dt) : Json();
  } else {
    j["penalty_scale_factor"] = nullptr;
    j["penalty_soft_scale"] = nullptr;
    j["penalty_soft_dt"] = nullptr;
  }
  j["threads"] = r.timing.threads;
  j["threads_min"] = r.timing.threads_min;
  j["wall_seconds"] = r.timing.wall_seconds;
  j["cpu_seconds"] = r.timing.cpu_seconds;
  j["peak_memory_bytes"] = r.timing.peak_memory_bytes;
  j["element_steps_per_second"] = r.timing.element_steps_per_second;
  j["initial_energy"] = r.initial_energy;
  j["energy_error_max"] = r.energy_error_max;
  j["penetration_max"] = r.penetration_max;
  j["displacement_max"] = r.displacement_max;
  Json drift = Json::object();
  drift["max"] = r.drift_max;
  drift["until"] = r.rest_until;
  drift["body"] = Json();
  drift["node"] = Json();
  with_model(pc, [&](const auto& m) {
    for (const auto& b : m.bodies)
      if (r.drift_node >= b.first_node && r.drift_node < b.first_node + b.num_nodes) {
        drift["body"] = b.name;
        drift["node"] = r.drift_node - b.first_node;
      }
  });
  j["drift"] = drift;
  j["friction_dissipation"] = r.friction_dissipation;
  j["contact_work"] = r.contact_work;
  // Stress peaks over every step (not over the samples), docs/outputs.md.
  auto where = [&](const StressPeak& p) {
    if (p.cell < 0) return Json();
    Json w = Json::object();
    w["body"] = with_model(pc, [&](const auto& m) { return m.bodies[p.body].name; });
    w["element"] = p.element;
    w["x"] = p.x;
    w["y"] = p.y;
    if (c.dimension == 3) w["z"] = p.z;
    return w;
  };
  auto by_measure = [](const VonMises2& maxima) {
    Json m = Json::object();
    for (int k = 0; k < kStressMeasures; ++k) m[stress_measure_name(static_cast<StressMeasure>(k))] = maxima[k];
    return m;
  };
  j["stress_measure"] = stress_measure_name(r.stress.measure);
  j["stress_every_step"] = pc.settings.stress_every_step;
  j["von_mises_max"] = r.stress.von_mises_max;
  j["von_mises_max_time"] = r.stress.von_mises_max_time;
  j["von_mises_max_at"] = where(r.stress.peak);
  j["von_mises_interior_max"] = r.stress.interior_peak.value;
  j["von_mises_interior_max_time"] = r.stress.interior_peak.time;
  j["von_mises_interior_max_at"] = where(r.stress.interior_peak);
  j["von_mises_sampled_max"] = by_measure(r.stress.sampled_max);
  j["total_mass"] = r.total_mass;
  j["contact_impulse_normal"] = r.contact.impulse_normal;
  j["contact_impulse_tangential"] = r.contact.impulse_tangential;
  const bool touched = r.contact.first_time >= 0.0;
  j["contact_start_time"] = touched ? Json(r.contact.first_time) : Json();
  j["contact_end_time"] = touched ? Json(r.contact.last_time) : Json();
  j["contact_duration"] = touched ? Json(r.contact.last_time - r.contact.first_time) : Json();
  // The mean normal contact force while in contact, the normal impulse over the time with an
  // active contact [N], and the largest summed normal force of the history samples [N].
  const double contact_time =
      r.dt_update_interval > 0 ? r.contact.time : static_cast<double>(r.contact.steps) * r.dt;
  j["contact_force_mean"] = contact_time > 0.0 ? Json(r.contact.impulse_normal / contact_time) : Json();
  double force_max = 0.0;
  if (r.history.rows() > 0)
    for (std::size_t i = 0, col = r.history.column("normal_force"); i < r.history.rows(); ++i)
      force_max = std::max(force_max, r.history.at(i, col));
  j["contact_force_max"] = force_max;
  Json ci = Json::object();
  ci["mean"] = r.contact.sweeps_mean;
  ci["max"] = r.contact.sweeps_max;
  ci["steps_with_contact"] = r.contact.steps;
  // The time with at least one active contact, steps x dt [s] (with a variable step the sum of
  // those steps): a contact duration that gates can compare across time steps and meshes.
  ci["contact_time"] = r.dt_update_interval > 0 ? r.contact.time : static_cast<double>(r.contact.steps) * r.dt;
  ci["unconverged_steps"] = r.contact.unconverged_steps;
  // Chatter of the active set: status changes (open, stick, slip) summed over every step, and
  // the steps that had any.
  ci["status_changes"] = r.contact.status_changes;
  ci["status_change_steps"] = r.contact.status_change_steps;
  ci["candidates"] = r.contact.candidates;
  j["contact_iterations"] = ci;
  const History& h = r.history;
  if (h.rows() > 0) {
    Json fin = Json::object();
    const std::size_t last = h.rows() - 1;
    std::vector<const char*> keys = {"time", "kinetic_energy", "strain_energy", "hourglass_energy",
                                     "external_work", "friction_dissipation", "contact_work", "total_energy",
                                     "energy_error", "momentum_x", "momentum_y"};
    if (c.dimension == 2)
      keys.push_back("angular_momentum");
    else
      keys.insert(keys.end(), {"momentum_z", "angular_momentum_x", "angular_momentum_y", "angular_momentum_z"});
    keys.push_back("contact_work_normal");
    for (const char* k : keys) fin[k] = h.at(last, h.column(k));
    // Each probe's displacement at the end (the external schemes' summaries have it too).
    for (const auto& p : pc.probes)
      for (const char* a : {"x", "y", "z"}) {
        if (*a == 'z' && c.dimension == 2) continue;
        const std::string col = p.name + "_u" + a;
        fin[col] = h.at(last, h.column(col));
      }
    j["final"] = fin;
    // Rebound velocity: the final linear momentum over the total mass [m/s].
    const bool massive = r.total_mass > 0.0;
    j["rebound_velocity_x"] = massive ? Json(h.at(last, h.column("momentum_x")) / r.total_mass) : Json();
    j["rebound_velocity_y"] = massive ? Json(h.at(last, h.column("momentum_y")) / r.total_mass) : Json();
    if (c.dimension == 3)
      j["rebound_velocity_z"] = massive ? Json(h.at(last, h.column("momentum_z")) / r.total_mass) : Json();
  }
  j["probes"] = probes_json(pc);
  j["history_rows"] = static_cast<long>(h.rows());
  j["field_files"] = static_cast<long>(r.fields.size());
  j["build"] = build_info();
  j["written_at"] = utc_now();
  return j;
}

namespace {

namespace fs = std::filesystem;

[[noreturn]] void cannot_write(const fs::path& path, const std::string& detail) {
  throw std::runtime_error("cannot write '" + path.string() + "': " + detail);
}

// `text` with every `from` replaced by `to`.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  for (auto at = text.find(from); !from.empty() && at != std::string::npos; at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
  return text;
}

}  // namespace

std::string output_folder_problem(const std::filesystem::path& dir) {
  if (dir.empty()) return "empty; give a folder name";
  for (fs::path p = dir; !p.empty(); p = p.parent_path()) {
    std::error_code ec;
    const fs::file_status st = fs::status(p, ec);
    if (!ec && fs::exists(st) && !fs::is_directory(st))
      return p == dir ? "is a file, not a folder" : "'" + p.string() + "' is a file, not a folder";
    if (p == p.parent_path()) break;
  }
  return {};
}

void write_run_outputs(const std::filesystem::path& dir, const PreparedCase& pc, const RunResult& r) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) cannot_write(dir, "cannot create the folder: " + ec.message());
  // Stale results of an earlier run in the same folder must not describe this one: summary.json,
  // which marks a finished run, goes first. Staging folders of killed runs go too.
  for (const char* name : {"summary.json", "history.csv"})
    if (fs::remove(dir / name, ec); ec) cannot_write(dir / name, "cannot remove the earlier one: " + ec.message());
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.path().filename().string().rfind(".staging-", 0) == 0) fs::remove_all(e.path(), ec);
  if (fs::remove_all(dir / "fields", ec); ec) cannot_write(dir / "fields", "cannot remove the earlier one: " + ec.message());

  // Every file is written into a staging folder first, then moved into place, summary.json last:
  // a failure anywhere leaves none of this run's outputs in `dir`.
  const fs::path stage = dir / (".staging-" + std::to_string(getpid()));
  try {
    if (!fs::create_directory(stage, ec) && ec) cannot_write(stage, ec.message());
    write_file_atomic(stage / "history.csv", format_csv(r.history.columns, r.history.values));
    if (!r.fields.empty()) {
      std::vector<std::pair<double, std::string>> series;
      for (const auto& f : r.fields) {
        char name[64];
        std::snprintf(name, sizeof name, "_%08ld.vtu", f.step);
        const std::string file = pc.spec.name + name;
        write_file_atomic(stage / "fields" / file,
                          pc.dimension() == 3 ? format_vtu_snapshot3(pc, f) : format_vtu_snapshot(pc, f));
        series.emplace_back(f.time, file);
      }
      write_file_atomic(stage / "fields" / "fields.pvd", format_pvd(series));
    }
    write_file_atomic(stage / "summary.json", dump_json(run_summary(pc, r)));
  } catch (const std::exception& e) {
    fs::remove_all(stage, ec);
    throw std::runtime_error(replaced(e.what(), stage.string(), dir.string()));  // name the files as the reader knows them
  }
  std::vector<fs::path> moved;
  for (const char* name : {"history.csv", "fields", "summary.json"}) {
    if (!fs::exists(stage / name)) continue;
    fs::rename(stage / name, dir / name, ec);
    if (ec) {
      const std::string detail = ec.message();
      for (const fs::path& m : moved) fs::remove_all(m, ec);
      fs::remove_all(stage, ec);
      cannot_write(dir / name, detail);
    }
    moved.push_back(dir / name);
  }
  fs::remove(stage, ec);
}

std::string one_line_summary(const PreparedCase& pc, const RunResult& r, const std::string& dir) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "%s: %s  t=%.4g s  %ld steps of %.4g s  %d cells  %.3g s wall  %.3g element-steps/s"
                "  energy_error_max=%.3g  penetration_max=%.3g m  von_mises_max=%.4g Pa",
                pc.spec.name.c_str(), r.status == RunStatus::ok ? "ok" : "DIVERGED", r.end_time,
                r.steps, r.dt, with_model(pc, [](const auto& m) { return m.num_cells(); }), r.timing.wall_seconds, r.timing.element_steps_per_second,
                r.energy_error_max, r.penetration_max, r.stress.von_mises_max);
  std::string s = buf;
  if (r.dt_update_interval > 0) {
    std::snprintf(buf, sizeof buf, " (variable: %.4g ... %.4g s)", r.dt_min, r.dt_max);
    s.insert(s.find(" s  ", s.find(" steps of ")) + 2, buf);
  }
  if (r.status == RunStatus::diverged) s += "  (" + r.reason + ")";
  return s + "  -> " + dir;
}

}  // namespace ricochet
