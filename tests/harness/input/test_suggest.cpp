// "Did you mean" (harness/input/suggest.hpp): the edit distance and which names count as a
// likely typo.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "harness/input/suggest.hpp"

using namespace ricochet;

TEST(Suggest, EditDistanceCountsEditsAndAdjacentTranspositions) {
  EXPECT_EQ(edit_distance("dt", "dt"), 0);
  EXPECT_EQ(edit_distance("dtt", "dt"), 1);           // insertion
  EXPECT_EQ(edit_distance("frction", "friction"), 1);  // deletion
  EXPECT_EQ(edit_distance("yuong", "young"), 1);       // transposition
  EXPECT_EQ(edit_distance("youmg", "young"), 1);       // substitution
  EXPECT_EQ(edit_distance("", "abc"), 3);
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3);
}

TEST(Suggest, OnlyLikelyTyposAreSuggested) {
  const std::vector<std::string> keys = {"end", "dt", "dt_safety", "stress_measure", "interval"};
  EXPECT_EQ(closest_name("dtt", keys), "dt");
  EXPECT_EQ(closest_name("ennd", keys), "end");
  EXPECT_EQ(closest_name("stres_mesure", keys), "stress_measure");  // 2 edits in 12 characters
  EXPECT_EQ(closest_name("intreval", keys), "interval");
  EXPECT_EQ(closest_name("zzzzzz", keys), "");
  EXPECT_EQ(closest_name("xy", keys), "");       // 2 edits from "dt": too many for 2 characters
  EXPECT_EQ(closest_name("dt", keys), "");       // a known name is no typo
  EXPECT_EQ(did_you_mean("dtt", keys), " (did you mean \"dt\"?)");
  EXPECT_EQ(did_you_mean("zzzzzz", keys), "");
}
