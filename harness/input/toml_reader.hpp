// Validating access to one TOML table of a case file. Every accessor checks type and range
// and throws InputError "FILE:LINE: KEY: what is wrong; allowed: ..."; finish() rejects the
// keys nobody read, listing the keys that are allowed. Values set from the command line
// (--set) are reported as "--set KEY" instead of a line.
#pragma once

#include <toml++/toml.h>

#include <cstdint>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "harness/input/input_error.hpp"
#include "solver/core/types.hpp"

namespace ricochet {

struct Range {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false, hi_open = false;
  static Range positive() { return {0.0, std::numeric_limits<double>::infinity(), true, false}; }
  static Range non_negative() { return {0.0, std::numeric_limits<double>::infinity(), false, false}; }
  static Range closed(double a, double b) { return {a, b, false, false}; }
  static Range open(double a, double b) { return {a, b, true, true}; }
  bool contains(double x) const;
  std::string describe() const;  // e.g. "> 0", "in [0, 1]", "in (-1, 0.5)"
};

// Parses TOML text; a syntax error is an InputError "FILE:LINE: TOML syntax error: ...".
toml::table parse_toml(std::string_view text, const std::string& file);
// The same for a file; `what` names it when it cannot be opened ("FILE: cannot open case file").
toml::table parse_toml_file(const std::string& file, const std::string& what);

// "a table", "an array", "a string", "an integer", "a number", "a boolean" or "a date/time":
// the kind of a TOML value, for error messages.
std::string type_name(const toml::node& n);

// The largest integer magnitude below which every integer is a double: 2^53.
inline constexpr std::int64_t kMaxExactInteger = std::int64_t{1} << 53;

// The double of a number node (an integer or a float), or empty for an integer beyond
// +-kMaxExactInteger (toml++ gives no double for those rather than round them) and for any
// other kind of node.
std::optional<double> exact_number(const toml::node& n);

// Shared by all readers of one case file.
struct CaseContext {
  std::string file;                 // as given on the command line
  std::set<std::string> overridden;  // dotted keys set by --set
};

class TableReader {
 public:
  TableReader(const toml::table& table, std::string path, const CaseContext& ctx);

  bool has(std::string_view key) const;
  bool is_text(std::string_view key) const;  // present and a string
  double number(std::string_view key, Range r) const;
  double number(std::string_view key, double fallback, Range r) const;
  long integer(std::string_view key, long fallback, long lo, long hi) const;
  bool boolean(std::string_view key, bool fallback) const;
  std::string text(std::string_view key) const;
  std::string text(std::string_view key, std::string fallback) const;
  std::string choice(std::string_view key, std::string fallback,
                     const std::vector<std::string>& allowed) const;
  Vec2 vec2(std::string_view key, Vec2 fallback) const;
  Vec2 vec2(std::string_view key) const;
  // A vector of `dim` = 2 ([x, y], z = 0; vec2's checks and messages) or 3 ([x, y, z]) finite
  // numbers.
  Vec3 vec(std::string_view key, int dim) const;
  Vec3 vec(std::string_view key, int dim, Vec3 fallback) const;
  std::vector<double> numbers(std::string_view key, Range each) const;  // empty if absent
  // A point [x, y] of two finite numbers given as the array `a` found under `key` (e.g. an
  // element of a list of points); errors name `key`.
  Vec2 point(std::string_view key, const toml::array& a) const;
  // A string or an array of non-empty strings; empty if absent.
  std::vector<std::string> texts(std::string_view key) const;
  std::optional<TableReader> table(std::string_view key) const;
  std::vector<TableReader> tables(std::string_view key) const;  // array of tables; empty if absent
  std::vector<std::string> keys() const;  // all keys of this table (marks none as read)
  // A table taken as it is, whatever it holds, as a JSON object's text ("{}" if absent); for
  // tables whose keys the harness hands on unread (external.options). Non-finite numbers are
  // refused (JSON has none).
  std::string table_as_json(std::string_view key) const;

  // Throws for the first key that no accessor asked for.
  void finish() const;

  // Key path of `key` inside this table, e.g. "bodies[0].material.young".
  std::string key_path(std::string_view key) const;
  [[noreturn]] void fail(std::string_view key, const std::string& what) const;
  const std::string& path() const { return path_; }

 private:
  const toml::node& require(std::string_view key) const;
  const toml::node* find(std::string_view key) const;
  std::string where(std::string_view key) const;

  const toml::table* table_;
  std::string path_;
  const CaseContext* ctx_;
  mutable std::set<std::string, std::less<>> read_;
};

}  // namespace ricochet
