// A case file, read and validated: typed values only, every default applied. The keys, units,
// defaults and ranges are documented in docs/case-format.md.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <toml++/toml.h>

#include "harness/input/mesh_generators.hpp"
#include "harness/input/mesh_generators3.hpp"
#include "harness/outputs/vtu_writer.hpp"
#include "solver/schemes/implicit.hpp"
#include "solver/model/model.hpp"

namespace ricochet {

// The time-integration scheme of a case (case key `scheme`, docs/case-format.md), parsed once.
enum class Scheme {
  plain_explicit,    // "explicit": central differences, no contact
  semi_explicit,     // "semi_explicit": central differences, bi-potential contact (the paper's)
  implicit,          // "implicit": the first-order theta-scheme
  explicit_penalty,  // "explicit_penalty": central differences, penalty springs
  external,          // any other name, with [external]: an external code through an adapter (docs/peers.md)
};

// The case-file name of a scheme: "explicit", "semi_explicit", "implicit", "explicit_penalty",
// "external".
const char* scheme_name(Scheme s);

// The scheme of a case-file name; the reader has checked it is one of the four.
Scheme scheme_from_name(const std::string& name);

struct GmshFile {
  std::filesystem::path path;  // resolved against the case file's folder
};

// `extrude = {thickness, layers}` of a mesh table: a 2D mesh through z in [0, thickness].
struct ExtrusionSpec {
  double thickness = 0.0;  // [m]
  int layers = 1;
};

struct MeshSpec {
  std::string name;
  // BoxSpec, BallSpec: the 3D `generator = "box"`, `"ball"`; a GmshFile holds 2D or 3D cells
  // (`dimension`).
  std::variant<RectangleSpec, ArcPlateSpec, DiskSpec, GmshFile, BoxSpec, BallSpec> source;
  std::optional<ExtrusionSpec> extrude;  // a 2D source made 3D
  int dimension = 2;             // of the mesh this builds: 3 for a box, an extrusion or a 3D Gmsh file
  double distort = 0.0;          // generated 2D meshes: interior nodes moved by up to this x h [-]
  std::uint64_t seed = 1;        // of the distortion's random numbers (distort_mesh)
  double scale = 1.0;            // coordinates multiplied by this [-]
  double rotate = 0.0;           // then rotated counterclockwise (about rotate_axis in 3D) by this [degrees]
  Vec3 rotate_axis = Vec3::UnitZ();  // 3D: the rotation's axis (normalized on read)
  Vec3 rotate_about = Vec3::Zero();  // about this point (of the scaled mesh) [m]; z = 0 in 2D
  Vec3 offset = Vec3::Zero();    // then translated by this [m]; z = 0 in 2D
  std::string where;             // key path for error messages, e.g. "meshes.M1"
};

struct MaterialSpec {
  std::string model = "saint_venant_kirchhoff";  // or "neo_hookean", "blatz_ko", "mooney_rivlin"
  double young = 0.0;    // [Pa] (saint_venant_kirchhoff, neo_hookean)
  double poisson = 0.0;  // [-]  (saint_venant_kirchhoff, neo_hookean)
  double shear_modulus = 0.0;  // [Pa] (blatz_ko)
  double c10 = 0.0, c01 = 0.0, bulk_modulus = 0.0;  // [Pa] (mooney_rivlin)
  double density = 0.0;  // [kg/m^3]
};

struct BoxNodeSet {
  std::string name;
  Vec3 lo, hi;  // (xmin, ymin, zmin), (xmax, ymax, zmax) in reference coordinates [m]; 2D: z 0
};

struct BodySpec {
  std::string name;
  std::string mesh;  // key of CaseSpec::meshes
  // 2D: "q4" (2x2 Gauss) or "q4_hourglass" (1 point + FB); 3D: "hex8" (2x2x2 Gauss) or
  // "hex8_hourglass" (1 point + FB). Triangles and tetrahedra have one formulation.
  std::string element = "q4";
  HourglassControl hourglass;
  MaterialSpec material;
  double thickness = 1.0;             // [m] (2D)
  Vec3 velocity = Vec3::Zero();       // [m/s]; z = 0 in 2D
  // About rotation_center [rad/s]: 2D the counterclockwise rate (in z), 3D the vector omega.
  Vec3 angular_velocity = Vec3::Zero();
  std::optional<Vec3> rotation_center;  // [m]; default: the body's centre of mass
  std::vector<BoxNodeSet> node_sets;
  std::string where;
};

struct BoundarySpec {
  std::string body;
  std::string nodes;  // node set of that body
  PrescribedDof::Kind kind = PrescribedDof::Kind::velocity;
  std::optional<double> x, y, z;  // [m/s] or [m]; absent = that direction is free (z: 3D)
  double ramp = 0.0;           // [s]
  std::string where;
};

// [[initial_velocity]]: the initial velocity of one node set, replacing the body's.
struct InitialVelocitySpec {
  std::string body;
  std::string nodes;  // node set of that body
  Vec3 velocity = Vec3::Zero();  // [m/s]; z = 0 in 2D
  std::string where;
};

// [[loads]]: a total force on one node set, ramped up in time (docs/case-format.md).
struct LoadSpec {
  std::string body;
  std::string nodes;             // node set of that body
  Vec3 force = Vec3::Zero();     // total over the set [N]; z = 0 in 2D
  bool by_mass = true;           // shared by lumped mass (true) or equally (false)
  double start = 0.0;            // [s]
  double ramp = 0.0;             // [s]
  std::string where;
};

// [relaxation]: a quasi-static start (solver/schemes/relaxation.hpp).
struct RelaxationSpec {
  bool enabled = false;
  double tolerance = 1e-6;  // [-]
  long max_steps = 100000;
};

struct ProbeSpec {
  std::string name;
  std::string body;
  std::optional<Vec3> point;  // nearest node to this reference point [m]; z = 0 in 2D
  std::string node_set;       // or the first node of this set
  std::string where;
};

struct ObstacleSpec {
  std::string name;
  Vec2 point = Vec2::Zero();    // [m]
  Vec2 normal = Vec2::UnitY();  // normalized on read
  Obstacle shape;               // 2D: the checked geometry of any type (line: same point, normal)
  Obstacle3 shape3;             // 3D: the checked geometry (plane, sphere, box, cylinder)
  double friction = 0.0;        // mu for every body [-]
  std::map<std::string, double> friction_by_body;  // per-body mu [-]
  std::string where;
};

// Contact between two bodies, node to segment (solver/contact/body_contact.hpp).
struct ContactPairSpec {
  std::string slave;       // body whose boundary nodes are checked
  std::string master;      // body whose boundary segments they are checked against
  double friction = 0.0;   // mu [-]
  bool two_pass = false;   // also the master's nodes against the slave's segments
  std::string name;        // the interface's name (history columns); default "<slave>_<master>"
  std::string where;
};

// [external]: the adapter that runs an external code on the case (a `scheme` named other than
// ricochet's own; docs/peers.md). The command's placeholders ({python}, {adapters}, {case_dir}) are resolved
// when the run starts (harness/external/external_run.hpp).
struct ExternalSpec {
  std::string adapter;               // a shipped adapter's name (adapters/<name>.py); empty with `command`
  std::vector<std::string> command;  // the program and its first arguments; empty with `adapter`
  std::string name;                  // the case's `scheme`: the run's scheme name in summary.json
  double timeout = 3600.0;           // wall-clock limit [s]
  std::string options_json = "{}";   // external.options as a JSON object, handed over as it is
};

// [limits]: ceilings on what a run may plan, checked before it starts (harness/input/run_plan.hpp,
// docs/reliability.md). They guard against a typo in time.end, time.dt or a mesh size turning
// into a run of years or an allocation of terabytes; each can be raised.
struct RunLimits {
  double max_steps = 1e8;         // ceil(time.end / dt) [steps]
  double max_history_rows = 1e6;  // rows of history.csv [-]
  double max_memory_gib = 64.0;   // estimated memory of the run [GiB]; read: default_max_memory_gib()
};

struct CaseSpec {
  std::string file;  // as given
  std::string name;
  std::string description;
  std::vector<std::string> overrides;  // the --set arguments, in order

  Scheme scheme = Scheme::plain_explicit;
  // 2 or 3: that of the meshes (every mesh of a case has the same; docs/case-format.md, 3D cases).
  int dimension = 2;
  PlaneMode plane = PlaneMode::stress;  // 2D
  Vec3 gravity = Vec3::Zero();  // [m/s^2]; z = 0 in 2D
  // [scene_rotation] (3D): every position and direction of the case turned by this rotation
  // (meshes after their own transforms, velocities, gravity, loads, obstacles, probe points);
  // node-set boxes select nodes before it. Empty: none. A frame-invariance check in a key.
  std::optional<Mat3> scene_rotation;
  // R v with the scene rotation, v itself without one.
  Vec3 turned(const Vec3& v) const { return scene_rotation ? Vec3(*scene_rotation * v) : v; }

  std::map<std::string, MeshSpec> meshes;
  std::string default_mesh;  // top-level `mesh`
  std::vector<BodySpec> bodies;
  std::vector<BoundarySpec> boundaries;
  std::vector<InitialVelocitySpec> initial_velocities;
  std::vector<LoadSpec> loads;
  RelaxationSpec relaxation;
  std::vector<ObstacleSpec> obstacles;
  std::vector<ContactPairSpec> contact_pairs;
  ContactSettings contact;
  ImplicitSettings implicit;
  PenaltySettings penalty;
  ExternalSpec external;  // scheme = "external" only

  double end_time = 0.0;          // [s]
  std::optional<double> dt;       // [s]; absent = automatic
  double dt_safety = 0.9;         // [-]
  int dt_update_interval = 0;     // [steps]; > 0: the automatic step recomputed every this many steps
  double dt_min_ratio = 0.01;     // [-]; variable step: the floor, as a fraction of the first step

  double sample_interval = 0.0;   // [s]
  std::vector<double> field_times;  // [s]
  StressMeasure stress_measure = StressMeasure::cauchy;  // of von_mises_max and the fields
  bool stress_every_step = true;  // von_mises_max over every step (else over the samples)
  // How fields/*.vtu store their arrays: output.field_format and output.field_compression.
  VtuFormat field_format{VtuEncoding::binary, VtuCompression::zlib};
  std::vector<ProbeSpec> probes;

  double energy_growth_limit = 2.0;  // [-]
  int monitor_every = 50;            // [steps]

  int threads = 0;  // OpenMP threads of the run: 0 = all cores, else 1 ... kMaxThreads (threads.hpp)
  bool adapt_threads = true;  // fewer threads while other processes hold the cores (threads.hpp)
  RunLimits limits;
};

// The folder of the shipped adapters (adapters/ of the source tree; $RICOCHET_ADAPTERS if set).
std::filesystem::path shipped_adapters_dir();

// Parses FILE, applies the --set overrides ("key=value", TOML value syntax, or a bare word
// taken as a string), validates everything and returns the typed case. Throws InputError.
CaseSpec read_case(const std::string& file, const std::vector<std::string>& overrides);
// The same for case TEXT (the fuzz target, tests/fuzz/); `file` names it in messages, and mesh
// files are resolved against its folder as for a real file.
CaseSpec read_case_text(std::string_view text, const std::string& file,
                        const std::vector<std::string>& overrides);

// "bodies[0].material.young" or "bodies.0.material.young" -> {"bodies", "0", "material", "young"}.
std::vector<std::string> split_key(const std::string& key);

// Applies one "key.path=value" override to a parsed document (exposed for tests).
// Returns the dotted key. Throws InputError naming the argument.
std::string apply_override(toml::table& doc, const std::string& file, const std::string& arg);

}  // namespace ricochet
