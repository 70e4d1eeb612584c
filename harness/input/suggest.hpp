// "Did you mean": the known name closest to a misspelt one, for the one-line input errors
// (input_error.hpp). Closeness is the optimal-string-alignment edit distance (insertions,
// deletions, substitutions and transpositions of two adjacent characters, each 1), and a name
// is suggested only when it is a likely typo: at most 1 edit for names of up to 5 characters,
// 2 up to 8, 3 beyond.
#pragma once

#include <algorithm>
#include <string>
#include <string_view>
#include <vector>

namespace ricochet {

inline int edit_distance(std::string_view a, std::string_view b) {
  const std::size_t n = a.size(), m = b.size();
  std::vector<int> d((n + 1) * (m + 1));
  auto at = [&](std::size_t i, std::size_t j) -> int& { return d[i * (m + 1) + j]; };
  for (std::size_t i = 0; i <= n; ++i) at(i, 0) = static_cast<int>(i);
  for (std::size_t j = 0; j <= m; ++j) at(0, j) = static_cast<int>(j);
  for (std::size_t i = 1; i <= n; ++i)
    for (std::size_t j = 1; j <= m; ++j) {
      const int cost = a[i - 1] == b[j - 1] ? 0 : 1;
      int v = std::min({at(i - 1, j) + 1, at(i, j - 1) + 1, at(i - 1, j - 1) + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) v = std::min(v, at(i - 2, j - 2) + 1);
      at(i, j) = v;
    }
  return at(n, m);
}

// The candidate closest to `name` if it is a likely typo of it (see above), else "". Ties go
// to the first candidate.
template <class Names>
std::string closest_name(std::string_view name, const Names& candidates) {
  const int limit = name.size() <= 5 ? 1 : name.size() <= 8 ? 2 : 3;
  std::string best;
  int best_d = limit + 1;
  for (const auto& c : candidates) {
    const int d = edit_distance(name, c);
    if (d > 0 && d < best_d) {
      best_d = d;
      best = std::string(c);
    }
  }
  return best;
}

// " (did you mean \"x\"?)" for the closest candidate, or "" when none is close.
template <class Names>
std::string did_you_mean(std::string_view name, const Names& candidates) {
  const std::string c = closest_name(name, candidates);
  return c.empty() ? "" : " (did you mean \"" + c + "\"?)";
}

}  // namespace ricochet
