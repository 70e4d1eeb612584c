#include "harness/input/toml_reader.hpp"

#include "harness/input/suggest.hpp"

#include <cmath>
#include <functional>
#include <cstdint>
#include <optional>
#include <filesystem>
#include <sstream>

namespace ricochet {
namespace {

std::string fmt(double x) {
  std::ostringstream s;
  s.precision(12);
  s << x;
  return s.str();
}

std::string show(const toml::node& n) {
  std::ostringstream s;
  if (const auto* t = n.as_string())
    s << '"' << t->get() << '"';
  else if (const auto* i = n.as_integer())
    s << i->get();  // exact, also beyond what a double holds
  else if (const auto* f = n.as_floating_point())
    s << fmt(f->get());
  else
    s << type_name(n);
  return s.str();
}

// "a number > 0", "a finite number", ...: what a number key allows.
std::string a_number(const Range& r) {
  const std::string d = r.describe();
  return d == "a finite number" ? d : "a number " + d;
}

std::string beyond_double(const toml::node& n) {
  return "got the integer " + show(n) + ", beyond +-2^53 = 9007199254740992 where a double holds every integer; "
         "write a number that large with an exponent (e.g. 9.2e18)";
}

}  // namespace

std::optional<double> exact_number(const toml::node& n) {
  if (const auto* i = n.as_integer()) {
    const std::int64_t x = i->get();
    if (x > kMaxExactInteger || x < -kMaxExactInteger) return std::nullopt;
    return static_cast<double>(x);
  }
  if (const auto* f = n.as_floating_point()) return f->get();
  return std::nullopt;
}

toml::table parse_toml(std::string_view text, const std::string& file) {
  try {
    return toml::parse(text, file);
  } catch (const toml::parse_error& e) {
    throw InputError(file + ":" + std::to_string(e.source().begin.line) + ": TOML syntax error: " +
                     std::string(e.description()));
  }
}

toml::table parse_toml_file(const std::string& file, const std::string& what) {
  if (!std::filesystem::is_regular_file(file)) throw InputError(file + ": cannot open " + what);
  try {
    return toml::parse_file(file);
  } catch (const toml::parse_error& e) {
    throw InputError(file + ":" + std::to_string(e.source().begin.line) + ": TOML syntax error: " +
                     std::string(e.description()));
  }
}

std::string type_name(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::table: return "a table";
    case toml::node_type::array: return "an array";
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a number";
    case toml::node_type::boolean: return "a boolean";
    default: return "a date/time";
  }
}

bool Range::contains(double x) const {
  if (!std::isfinite(x)) return false;
  const bool above = lo_open ? x > lo : x >= lo;
  const bool below = hi_open ? x < hi : x <= hi;
  return above && below;
}

std::string Range::describe() const {
  const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
  if (has_lo && !has_hi) return std::string(lo_open ? "> " : ">= ") + fmt(lo);
  if (!has_lo && has_hi) return std::string(hi_open ? "< " : "<= ") + fmt(hi);
  if (!has_lo && !has_hi) return "a finite number";
  return std::string("in ") + (lo_open ? "(" : "[") + fmt(lo) + ", " + fmt(hi) + (hi_open ? ")" : "]");
}

TableReader::TableReader(const toml::table& table, std::string path, const CaseContext& ctx)
    : table_(&table), path_(std::move(path)), ctx_(&ctx) {}

std::string TableReader::key_path(std::string_view key) const {
  return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
}

std::string TableReader::where(std::string_view key) const {
  const std::string kp = key_path(key);
  // An overridden key, or a key inside an overridden table, came from the command line.
  for (const auto& o : ctx_->overridden)
    if (kp == o || kp.rfind(o + ".", 0) == 0 || kp.rfind(o + "[", 0) == 0)
      return ctx_->file + ": --set " + o + ": " + kp;
  const toml::node* n = find(key);
  const auto& src = n ? n->source() : table_->source();
  if (src.begin.line > 0) return ctx_->file + ":" + std::to_string(src.begin.line) + ": " + kp;
  return ctx_->file + ": " + kp;
}

void TableReader::fail(std::string_view key, const std::string& what) const {
  throw InputError(where(key) + ": " + what);
}

const toml::node* TableReader::find(std::string_view key) const { return table_->get(key); }

bool TableReader::has(std::string_view key) const { return find(key) != nullptr; }

bool TableReader::is_text(std::string_view key) const {
  const toml::node* n = find(key);
  return n && n->is_string();
}

const toml::node& TableReader::require(std::string_view key) const {
  read_.insert(std::string(key));
  const toml::node* n = find(key);
  if (!n) {
    // A key of the table close to the missing one is likely it, misspelt.
    std::vector<std::string> present;
    for (auto&& [k, v] : *table_) present.emplace_back(k.str());
    // Reported at the typo itself: the key that is there is the one to fix.
    const std::string typo = closest_name(key, present);
    if (!typo.empty())
      fail(typo, "unknown key (did you mean \"" + std::string(key) + "\"? it is required here and missing)");
    fail(key, "missing required key");
  }
  return *n;
}

double TableReader::number(std::string_view key, Range r) const {
  const toml::node& n = require(key);
  if (!n.is_number()) fail(key, "expected " + a_number(r) + "; got " + type_name(n));
  const std::optional<double> x = exact_number(n);
  if (!x) fail(key, "expected " + a_number(r) + "; " + beyond_double(n));
  if (!r.contains(*x)) fail(key, "expected " + a_number(r) + "; got " + show(n));
  return *x;
}

double TableReader::number(std::string_view key, double fallback, Range r) const {
  read_.insert(std::string(key));
  return has(key) ? number(key, r) : fallback;
}

long TableReader::integer(std::string_view key, long fallback, long lo, long hi) const {
  read_.insert(std::string(key));
  const toml::node* n = find(key);
  if (!n) return fallback;
  const std::string allowed = "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  const auto* i = n->as_integer();
  if (!i) fail(key, "expected " + allowed + "; got " + show(*n));
  const std::int64_t x = i->get();
  if (x < lo || x > hi) fail(key, "expected " + allowed + "; got " + std::to_string(x));
  return static_cast<long>(x);
}

std::vector<std::string> TableReader::texts(std::string_view key) const {
  read_.insert(std::string(key));
  const toml::node* n = find(key);
  if (!n) return {};
  const std::string allowed = "a string or an array of non-empty strings";
  std::vector<std::string> out;
  if (const auto* t = n->as_string()) {
    out.push_back(t->get());
  } else if (const toml::array* a = n->as_array()) {
    for (const toml::node& e : *a) {
      const auto* t = e.as_string();
      if (!t) fail(key, "expected " + allowed + "; got an element that is " + type_name(e));
      out.push_back(t->get());
    }
  } else {
    fail(key, "expected " + allowed + "; got " + show(*n));
  }
  for (const std::string& s : out)
    if (s.empty()) fail(key, "expected " + allowed + "; got an empty string");
  return out;
}

std::string TableReader::table_as_json(std::string_view key) const {
  read_.insert(std::string(key));
  const toml::node* n = find(key);
  if (!n) return "{}";
  const toml::table* t = n->as_table();
  if (!t) fail(key, "expected a table; got " + show(*n));
  // JSON has no infinities or NaN: refuse them here rather than hand on what cannot be read.
  std::string bad;
  std::function<void(const toml::node&)> walk = [&](const toml::node& v) {
    if (const auto* f = v.as_floating_point(); f && !std::isfinite(f->get())) bad = "a non-finite number";
    if (const auto* a = v.as_array())
      for (const toml::node& e : *a) walk(e);
    if (const auto* sub = v.as_table())
      for (auto&& [k, e] : *sub) walk(e);
  };
  walk(*t);
  if (!bad.empty()) fail(key, "holds " + bad + "; its values are handed on as JSON, which has none");
  std::ostringstream os;
  os << toml::json_formatter{*t, toml::format_flags::none};
  return os.str();
}

bool TableReader::boolean(std::string_view key, bool fallback) const {
  read_.insert(std::string(key));
  const toml::node* n = find(key);
  if (!n) return fallback;
  const auto* b = n->as_boolean();
  if (!b) fail(key, "expected true or false; got " + show(*n));
  return b->get();
}

std::string TableReader::text(std::string_view key) const {
  const toml::node& n = require(key);
  const auto* t = n.as_string();
  if (!t) fail(key, "expected a string; got " + show(n));
  return t->get();
}

std::string TableReader::text(std::string_view key, std::string fallback) const {
  read_.insert(std::string(key));
  return has(key) ? text(key) : fallback;
}

std::string TableReader::choice(std::string_view key, std::string fallback,
                                const std::vector<std::string>& allowed) const {
  const std::string v = text(key, fallback);
  for (const auto& a : allowed)
    if (v == a) return v;
  std::string list;
  for (const auto& a : allowed) list += (list.empty() ? "\"" : ", \"") + a + "\"";
  fail(key, "got \"" + v + "\"; allowed: " + list);
}

Vec2 TableReader::vec2(std::string_view key) const {
  const toml::node& n = require(key);
  const toml::array* a = n.as_array();
  if (!a || a->size() != 2 || !(*a)[0].is_number() || !(*a)[1].is_number())
    fail(key, "expected an array of two numbers [x, y]; got " + show(n));
  return point(key, *a);
}

Vec2 TableReader::vec2(std::string_view key, Vec2 fallback) const {
  read_.insert(std::string(key));
  return has(key) ? vec2(key) : fallback;
}

std::vector<double> TableReader::numbers(std::string_view key, Range each) const {
  read_.insert(std::string(key));
  std::vector<double> out;
  const toml::node* n = find(key);
  if (!n) return out;
  const toml::array* a = n->as_array();
  const std::string allowed = "expected an array of numbers" + (each.describe() == "a finite number" ? std::string(" (finite)") : " " + each.describe());
  if (!a) fail(key, allowed + "; got " + show(*n));
  for (const auto& e : *a) {
    const std::optional<double> x = exact_number(e);
    if (e.is_integer() && !x) fail(key, allowed + "; element " + std::to_string(out.size()) + ": " + beyond_double(e));
    if (!x || !each.contains(*x)) fail(key, allowed + "; got an element " + show(e));
    out.push_back(*x);
  }
  return out;
}

Vec3 TableReader::vec(std::string_view key, int dim) const {
  if (dim == 2) {
    const Vec2 v = vec2(key);
    return Vec3(v.x(), v.y(), 0.0);
  }
  const toml::node& n = require(key);
  const toml::array* a = n.as_array();
  const char* expected = "expected an array of three numbers [x, y, z]";
  if (!a || a->size() != 3) fail(key, std::string(expected) + "; got " + show(n));
  Vec3 v;
  for (int d = 0; d < 3; ++d) {
    const toml::node& e = (*a)[static_cast<std::size_t>(d)];
    if (!e.is_number()) fail(key, std::string(expected) + "; got an element that is " + type_name(e));
    const std::optional<double> x = exact_number(e);
    if (!x) fail(key, std::string(expected) + "; " + beyond_double(e));
    v[d] = *x;
  }
  if (!v.allFinite()) fail(key, "expected finite numbers");
  return v;
}

Vec3 TableReader::vec(std::string_view key, int dim, Vec3 fallback) const {
  read_.insert(std::string(key));
  return has(key) ? vec(key, dim) : fallback;
}

Vec2 TableReader::point(std::string_view key, const toml::array& a) const {
  Vec2 v;
  for (int d = 0; d < 2; ++d) {
    const toml::node& e = a[static_cast<std::size_t>(d)];
    if (!e.is_number()) fail(key, "expected an array of two numbers [x, y]; got an element that is " + type_name(e));
    const std::optional<double> x = exact_number(e);
    if (!x) fail(key, "expected an array of two numbers [x, y]; " + beyond_double(e));
    v[d] = *x;
  }
  if (!v.allFinite()) fail(key, "expected finite numbers");
  return v;
}

std::optional<TableReader> TableReader::table(std::string_view key) const {
  read_.insert(std::string(key));
  const toml::node* n = find(key);
  if (!n) return std::nullopt;
  if (!n->is_table()) fail(key, "expected a table; got " + show(*n));
  return TableReader(*n->as_table(), key_path(key), *ctx_);
}

std::vector<TableReader> TableReader::tables(std::string_view key) const {
  read_.insert(std::string(key));
  std::vector<TableReader> out;
  const toml::node* n = find(key);
  if (!n) return out;
  const toml::array* a = n->as_array();
  if (!a) fail(key, "expected an array of tables ([[" + key_path(key) + "]]); got " + show(*n));
  for (std::size_t i = 0; i < a->size(); ++i) {
    const toml::table* t = (*a)[i].as_table();
    if (!t) fail(key, "expected an array of tables; element " + std::to_string(i) + " is " + show((*a)[i]));
    out.emplace_back(*t, key_path(key) + "[" + std::to_string(i) + "]", *ctx_);
  }
  return out;
}

std::vector<std::string> TableReader::keys() const {
  std::vector<std::string> k;
  for (auto&& [key, value] : *table_) k.emplace_back(key.str());
  return k;
}

void TableReader::finish() const {
  for (auto&& [key, value] : *table_) {
    if (read_.count(key.str())) continue;
    std::string allowed;
    for (const auto& r : read_) allowed += (allowed.empty() ? "" : ", ") + r;
    fail(key.str(), "unknown key" + did_you_mean(key.str(), read_) + "; allowed here: " + allowed);
  }
}

}  // namespace ricochet
