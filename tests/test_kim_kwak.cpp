// The Kim-Kwak-type problem cases/kim_kwak/rubber_groove.toml (docs/kim-kwak-type.md): a
// Blatz-Ko ball strikes a Mooney-Rivlin block in a rigid V groove (polyline) with a bump
// (circle), mu = 0.3 everywhere. The sweep's gates (ci/gates/kim_kwak.toml) check the energy,
// the penetration and the friction from summary.csv; this test checks from the history that the
// bodies do what the case says, in all three schemes: the ball is stopped and thrown back by
// the block (contact between the bodies), the block is shoved along the floor, trips over the
// bump and leaves the floor, and nothing ends inside the groove's floor.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "harness/input/case_setup.hpp"
#include "harness/input/case_spec.hpp"
#include "solver/schemes/explicit.hpp"

namespace ricochet {
namespace {

const std::string kCase = std::string(RICOCHET_SOURCE_DIR) + "/cases/kim_kwak/rubber_groove.toml";

std::vector<double> column(const History& h, const std::string& name) {
  const std::size_t c = h.column(name);
  std::vector<double> out(h.rows());
  for (std::size_t i = 0; i < h.rows(); ++i) out[i] = h.at(i, c);
  return out;
}

TEST(KimKwak, RubberGrooveStoryInAllSchemes) {
  for (const char* scheme : {"semi_explicit", "implicit", "explicit_penalty"}) {
    SCOPED_TRACE(scheme);
    const PreparedCase pc = prepare_case(read_case(kCase, {"scheme=\"" + std::string(scheme) + "\"", "output.fields=[]"}));
    const RunResult r = run_case(pc);
    ASSERT_EQ(r.status, RunStatus::ok) << r.reason;
    const History& h = r.history;
    const auto t = column(h, "time"), ball_vx = column(h, "ball_centre_vx");
    const auto corner_ux = column(h, "block_corner_ux"), corner_uy = column(h, "block_corner_uy");
    // The ball flies freely at 8 m/s until it meets the block at about 6.5 ms, and moves back
    // (vx < 0) once it has rebounded.
    double vx_before = 0.0;
    for (std::size_t i = 0; i < t.size() && t[i] <= 5e-3; ++i) vx_before = ball_vx[i];
    const double vx_end = ball_vx.back();
    std::printf("[kim_kwak] %s: ball vx %.3f m/s at 5 ms, %.3f m/s at the end; block corner moved "
                "(%.4f, %.4f) m; energy error max %.4f, penetration max %.2e m\n",
                scheme, vx_before, vx_end, corner_ux.back(), corner_uy.back(), r.energy_error_max,
                r.penetration_max);
    EXPECT_NEAR(vx_before, 8.0, 0.05);
    EXPECT_LT(vx_end, 0.0) << "thrown back by the block";
    // The block was shoved right by several centimetres and, after the bump, its struck corner
    // is off the floor.
    EXPECT_GT(corner_ux.back(), 0.05);
    EXPECT_GT(corner_uy.back(), 0.005);
  }
}

}  // namespace
}  // namespace ricochet
