// Checks shared by the sweep tests (harness/sweeps/).
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "harness/input/input_error.hpp"
#include "harness/sweeps/sweep.hpp"
#include "harness/sweeps/sweep_spec.hpp"

namespace ricochet::test_support {

// Expects read_sweep + expand + check_runs to reject the sweep file `file` (its text `sweep_text`,
// shown if it is accepted) with one line naming the file and each of `parts`.
inline void expect_sweep_rejected(const std::string& file, const std::string& sweep_text,
                                  const std::vector<std::string>& parts) {
  try {
    const SweepSpec spec = read_sweep(file);
    check_runs(spec, expand(spec));
    ADD_FAILURE() << "accepted: " << sweep_text;
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    EXPECT_NE(msg.find(file), std::string::npos) << "names the sweep file: " << msg;
    for (const auto& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << p << " in: " << msg;
  }
}

}  // namespace ricochet::test_support
