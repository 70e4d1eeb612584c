// Small case files that several tests run: plates of a few cells whose runs take milliseconds.
#pragma once

#include <string>

namespace ricochet::test_support {

// A rectangular plate, one body "b" on the generated mesh "m" (plus the mesh tables `meshes`),
// held at its left edge and moving upwards at `vy`, density 1000 kg/m^3; the text ends with
// "[time]" for the caller's time keys. Numbers are given as they are written in the file.
inline std::string held_plate_case(const std::string& name, const std::string& width, const std::string& height,
                                   int nx, int ny, const std::string& meshes, const std::string& vy,
                                   const std::string& young, const std::string& poisson) {
  return "name = \"" + name + "\"\nmesh = \"m\"\n[meshes.m]\ngenerator = \"rectangle\"\nwidth = " + width +
         "\nheight = " + height + "\nnx = " + std::to_string(nx) + "\nny = " + std::to_string(ny) + "\n" + meshes +
         "[[bodies]]\nname = \"b\"\nvelocity = [0.0, " + vy + "]\n[bodies.material]\nyoung = " + young +
         "\npoisson = " + poisson + "\ndensity = 1000.0\n" + R"([[boundary]]
nodes = "left"
type = "displacement"
x = 0.0
y = 0.0
[time]
)";
}

// The tiny vibrating plate of the sweep tests: 0.1 m x 0.05 m, 4 x 2 cells, set moving upwards at
// 1 m/s, so its probe and energy histories depend on the time step; 200 steps of 1e-5 s, history
// every 1e-4 s, probe P at the top right corner. With `bad_mesh` it also names a mesh `bad` whose
// file does not exist: the case passes validation, and a run that chooses it fails when it
// builds the mesh.
inline std::string tiny_plate_case(bool bad_mesh = true) {
  return held_plate_case("tiny", "0.1", "0.05", 4, 2, bad_mesh ? "[meshes.bad]\nfile = \"missing.msh\"\n" : "",
                         "1.0", "1e6", "0.3") +
         R"(end = 2e-3
dt = 1e-5
[output]
interval = 1e-4
[[output.probes]]
name = "P"
point = [0.1, 0.05]
)";
}

// The square plate of the stability tests, named `name`: 0.1 m x 0.1 m of cells x cells square Q4
// cells, moving up at 0.1 m/s (strains ~ v / c_p ~ 1e-3: the response is linear); plane stress,
// young = 1e7 Pa, nu = 0.25, c_p = 103 m/s; time.end = 0.05 s and no time.dt (the automatic
// step). With `probe`, history every 1e-3 s and probe P at the top right corner.
inline std::string square_plate_case(const std::string& name, int cells, bool probe) {
  std::string s = held_plate_case(name, "0.1", "0.1", cells, cells, "", "0.1", "1e7", "0.25") + "end = 0.05\n";
  if (probe) s += "[output]\ninterval = 1e-3\n[[output.probes]]\nname = \"P\"\npoint = [0.1, 0.1]\n";
  return s;
}

}  // namespace ricochet::test_support
