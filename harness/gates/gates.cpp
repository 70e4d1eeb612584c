#include "harness/gates/gates.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "harness/outputs/atomic_file.hpp"
#include "harness/outputs/csv_writer.hpp"
#include "harness/input/input_error.hpp"
#include "harness/input/toml_reader.hpp"

namespace ricochet {
namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kKinds = {"max", "min", "near", "ratio", "count", "pattern"};

// ---------------------------------------------------------------------------------------------
// Number formatting for messages.

// Exact: the shortest text that reads back to the same double (limits, references).
std::string exact(double x) {
  std::string s;
  append_number(s, x);
  return s;
}

// Three significant digits (margins, percentages, ratios).
std::string approx(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", x);
  return buf;
}

// A percentage: 3 significant digits, whole numbers from 100 on ("56", "10.2", "3000").
std::string pct(double p) {
  if (std::isfinite(p) && std::abs(p) >= 100.0) {
    char buf[48];
    std::snprintf(buf, sizeof buf, "%.0f", p);
    return buf;
  }
  return approx(p);
}

// " (by 0.0112, 56 %)" for an excess `by` over `limit`; the percentage is relative to |limit|.
std::string by_margin(double by, double limit) {
  std::string s = " (by " + approx(by);
  if (limit != 0.0 && std::isfinite(by)) s += ", " + pct(100.0 * by / std::abs(limit)) + " %";
  return s + ")";
}

std::string percent_of(double part, double whole) {
  if (whole == 0.0 || !std::isfinite(part)) return "";
  return ", " + pct(100.0 * part / std::abs(whole)) + " %";
}

// ---------------------------------------------------------------------------------------------
// Reading the gate file.

std::optional<MatchValue> match_value(const toml::node& n) {
  MatchValue v;
  if (const auto* t = n.as_string()) {
    v.text = t->get();
    v.number = parse_csv_number(v.text);
  } else if (const auto* i = n.as_integer()) {
    // Matched as text and, where a double holds it exactly, as a number (a CSV cell of a larger
    // integer is matched by its text alone).
    v.text = std::to_string(i->get());
    v.number = exact_number(n);
  } else if (const auto* f = n.as_floating_point()) {
    v.number = f->get();
    v.text = exact(*v.number);
  } else if (const auto* b = n.as_boolean()) {
    v.text = b->get() ? "true" : "false";
  } else {
    return std::nullopt;
  }
  return v;
}

// Flattens a selector table: nested tables give dotted column names, so
// `where = { time.dt = 1e-6 }` and `where = { "time.dt" = 1e-6 }` are the same selector.
// toml++ iterates a table in key order; selectors keep the file's order (for messages).
std::vector<std::pair<std::string_view, const toml::node*>> in_file_order(const toml::table& raw) {
  std::vector<std::pair<std::string_view, const toml::node*>> items;
  for (auto&& [key, node] : raw) items.emplace_back(key.str(), &node);
  std::stable_sort(items.begin(), items.end(), [](const auto& a, const auto& b) {
    const auto& pa = a.second->source().begin;
    const auto& pb = b.second->source().begin;
    return pa.line != pb.line ? pa.line < pb.line : pa.column < pb.column;
  });
  return items;
}

void flatten_selector(const TableReader& reader, const toml::table& raw, const std::string& prefix,
                      const CaseContext& ctx, Selector& out) {
  constexpr const char* allowed =
      "expected a string, a number, a boolean or a non-empty array of them (any of)";
  for (const auto& [key, node_ptr] : in_file_order(raw)) {
    const toml::node& node = *node_ptr;
    const std::string k(key);
    const std::string column = prefix.empty() ? k : prefix + "." + k;
    if (const toml::table* sub = node.as_table()) {
      flatten_selector(TableReader(*sub, reader.key_path(k), ctx), *sub, column, ctx, out);
      continue;
    }
    SelectorTerm term;
    term.column = column;
    if (const toml::array* a = node.as_array()) {
      if (a->empty()) reader.fail(k, std::string(allowed) + "; got an empty array");
      for (const auto& e : *a) {
        auto v = match_value(e);
        if (!v) reader.fail(k, std::string(allowed) + "; got an element that is " + type_name(e));
        term.any_of.push_back(std::move(*v));
      }
    } else {
      auto v = match_value(node);
      if (!v) reader.fail(k, std::string(allowed) + "; got " + type_name(node));
      term.any_of.push_back(std::move(*v));
    }
    for (const auto& t : out)
      if (t.column == column) reader.fail(k, "column '" + column + "' appears twice in this selector");
    out.push_back(std::move(term));
  }
}

// Reads the selector `key` of `parent` (a table of column = value). Absent: empty selector, or
// an error if `required`.
Selector read_selector(const TableReader& parent, const toml::table& parent_raw, std::string_view key,
                       const CaseContext& ctx, bool required) {
  Selector s;
  const auto reader = parent.table(key);  // checks that it is a table
  if (!reader) {
    if (required)
      parent.fail(key, "missing required key; expected a selector table { column = value, ... }");
    return s;
  }
  flatten_selector(*reader, *parent_raw.get(key)->as_table(), "", ctx, s);
  return s;
}

std::string line_of(const toml::node& n, const std::string& file) {
  const auto line = n.source().begin.line;
  return line > 0 ? file + ":" + std::to_string(line) : file;
}

Gate read_gate(const TableReader& g, const toml::table& raw, std::size_t index, const CaseContext& ctx) {
  Gate gate;
  gate.location = line_of(raw, ctx.file);
  if (!g.has("kind")) g.fail("kind", "missing required key; allowed: max, min, near, ratio, count, pattern");
  const std::string kind = g.choice("kind", "", kKinds);
  gate.kind = kind == "max"     ? GateKind::max
              : kind == "min"   ? GateKind::min
              : kind == "near"  ? GateKind::near
              : kind == "ratio" ? GateKind::ratio
              : kind == "count" ? GateKind::count
                                : GateKind::pattern;

  gate.where = read_selector(g, raw, "where", ctx, false);
  switch (gate.kind) {
    case GateKind::max:
    case GateKind::min:
      gate.column = g.text("column");
      gate.limit = g.number("limit", Range{});
      gate.strict = g.boolean("strict", false);
      gate.allow_empty = g.boolean("allow_empty", false);
      break;
    case GateKind::near:
      gate.column = g.text("column");
      gate.reference = g.number("reference", Range{});
      if (g.has("tolerance")) gate.tolerance = g.number("tolerance", Range::non_negative());
      if (g.has("rel_tolerance")) gate.rel_tolerance = g.number("rel_tolerance", Range::non_negative());
      g.number("tolerance", 0.0, Range::non_negative());  // mark both as allowed keys
      g.number("rel_tolerance", 0.0, Range::non_negative());
      if (!gate.tolerance && !gate.rel_tolerance)
        g.fail("rel_tolerance",
               "missing: a near gate needs tolerance (absolute) or rel_tolerance (relative to "
               "|reference|), or both");
      gate.allow_empty = g.boolean("allow_empty", false);
      break;
    case GateKind::ratio:
      gate.column = g.text("column");
      gate.numerator = read_selector(g, raw, "numerator", ctx, true);
      gate.denominator = read_selector(g, raw, "denominator", ctx, true);
      if (g.has("floor")) gate.floor = g.number("floor", Range{});
      if (g.has("ceiling")) gate.ceiling = g.number("ceiling", Range{});
      g.number("floor", 0.0, Range{});
      g.number("ceiling", 0.0, Range{});
      if (!gate.floor && !gate.ceiling)
        g.fail("floor", "missing: a ratio gate needs floor (ratio >= floor) or ceiling (ratio <= ceiling), or both");
      if (gate.floor && gate.ceiling && *gate.floor > *gate.ceiling)
        g.fail("ceiling", "ceiling " + exact(*gate.ceiling) + " is below floor " + exact(*gate.floor));
      break;
    case GateKind::count:
      if (g.has("min")) gate.min_rows = g.integer("min", 0, 0, LONG_MAX);
      if (g.has("max")) gate.max_rows = g.integer("max", 0, 0, LONG_MAX);
      g.integer("min", 0, 0, LONG_MAX);
      g.integer("max", 0, 0, LONG_MAX);
      if (!gate.min_rows && !gate.max_rows)
        g.fail("max", "missing: a count gate needs min or max (number of selected rows), or both");
      if (gate.min_rows && gate.max_rows && *gate.min_rows > *gate.max_rows)
        g.fail("max", "max " + std::to_string(*gate.max_rows) + " is below min " + std::to_string(*gate.min_rows));
      break;
    case GateKind::pattern: {
      gate.column = g.text("column", "status");
      const auto cells = g.tables("cells");
      if (!g.has("cells")) g.fail("cells", "missing required key; expected an array of { where = {...}, expect = \"...\" }");
      if (cells.empty()) g.fail("cells", "expected at least one cell { where = {...}, expect = \"...\" }");
      const toml::array& raw_cells = *raw.get("cells")->as_array();
      for (std::size_t c = 0; c < cells.size(); ++c) {
        PatternCell cell;
        cell.where = read_selector(cells[c], *raw_cells[c].as_table(), "where", ctx, true);
        cell.expect = cells[c].text("expect");
        cells[c].finish();
        gate.cells.push_back(std::move(cell));
      }
      break;
    }
  }
  if (gate.kind != GateKind::count && gate.column.empty())
    g.fail("column", "expected a column name; got an empty string");
  gate.name = g.text("name", "gate[" + std::to_string(index) + "] " + kind +
                                 (gate.column.empty() ? "" : " " + gate.column));
  if (gate.name.empty()) g.fail("name", "expected a non-empty name");
  g.finish();
  return gate;
}

// ---------------------------------------------------------------------------------------------
// Evaluation.

bool value_matches(const MatchValue& v, const std::string& cell) {
  if (v.number) {
    if (const auto x = parse_csv_number(cell)) {
      const double a = *v.number, b = *x;
      if (a == b) return true;
      return std::abs(a - b) <= 1e-12 * std::max(std::abs(a), std::abs(b));
    }
  }
  return v.text == cell;
}

std::string describe_selector(const Selector& s) {
  std::string out = "{";
  for (std::size_t i = 0; i < s.size(); ++i) {
    out += (i ? ", " : "") + s[i].column + " = ";
    if (s[i].any_of.size() == 1) {
      out += s[i].any_of[0].text;
    } else {
      out += "[";
      for (std::size_t j = 0; j < s[i].any_of.size(); ++j) out += (j ? ", " : "") + s[i].any_of[j].text;
      out += "]";
    }
  }
  return out + "}";
}

std::string missing_column(const CsvTable& t, const std::string& column, const std::string& role) {
  return "column '" + column + "' (" + role + ") is not in " + t.file + "; its columns: " + t.column_list();
}

// Rows of `from` that `s` selects; an error text if a column of `s` is not in the table.
std::vector<std::size_t> select(const CsvTable& t, const Selector& s, const std::vector<std::size_t>& from,
                                const std::string& role, std::string& error) {
  std::vector<std::size_t> cols;
  for (const auto& term : s) {
    const auto c = t.column_index(term.column);
    if (!c) {
      error = missing_column(t, term.column, role);
      return {};
    }
    cols.push_back(*c);
  }
  std::vector<std::size_t> rows;
  for (const std::size_t r : from) {
    bool all = true;
    for (std::size_t i = 0; i < s.size() && all; ++i) {
      const std::string& cell = t.rows[r][cols[i]];
      all = std::any_of(s[i].any_of.begin(), s[i].any_of.end(),
                        [&](const MatchValue& v) { return value_matches(v, cell); });
    }
    if (all) rows.push_back(r);
  }
  return rows;
}

std::string run_label(const CsvTable& t, std::size_t r) {
  const std::string* id = t.find(r, "run_id");
  if (id && !id->empty()) return "run " + *id;
  return "row at " + t.file + ":" + std::to_string(t.lines[r]);
}

std::string run_list(const CsvTable& t, const std::vector<std::size_t>& rows) {
  std::string s;
  const std::size_t shown = std::min<std::size_t>(rows.size(), 10);
  for (std::size_t i = 0; i < shown; ++i) s += (i ? ", " : "") + run_label(t, rows[i]);
  if (rows.size() > shown) s += ", ... (" + std::to_string(rows.size() - shown) + " more)";
  return s;
}

// The number in column `c` of row `r`, or nullopt with a failure text.
std::optional<double> numeric_cell(const CsvTable& t, std::size_t r, std::size_t c, std::string& failure) {
  const std::string& cell = t.rows[r][c];
  if (cell.empty()) {
    failure = run_label(t, r) + ": " + t.columns[c] + " is empty (no value)";
    return std::nullopt;
  }
  const auto x = parse_csv_number(cell);
  if (!x) failure = run_label(t, r) + ": " + t.columns[c] + " = '" + cell + "' is not a number";
  return x;
}

// A selector that must match exactly one row; nullopt with a failure text otherwise.
std::optional<std::size_t> single_row(const CsvTable& t, const Selector& s, const std::vector<std::size_t>& from,
                                      const std::string& role, std::string& failure) {
  std::string error;
  const auto rows = select(t, s, from, role, error);
  if (!error.empty()) {
    failure = error;
    return std::nullopt;
  }
  if (rows.size() == 1) return rows[0];
  if (rows.empty())
    failure = role + " " + describe_selector(s) + " matches no row; expected exactly one";
  else
    failure = role + " " + describe_selector(s) + " matches " + std::to_string(rows.size()) +
              " rows (" + run_list(t, rows) + "); expected exactly one";
  return std::nullopt;
}

void evaluate_bound(const CsvTable& t, const Gate& g, const std::vector<std::size_t>& rows, std::size_t c,
                    GateResult& res) {
  const bool is_max = g.kind == GateKind::max;
  const std::string op_ok = is_max ? (g.strict ? "<" : "<=") : (g.strict ? ">" : ">=");
  const std::string op_bad = is_max ? (g.strict ? ">=" : ">") : (g.strict ? "<=" : "<");
  double best_margin = std::numeric_limits<double>::infinity();
  std::string worst;
  for (const std::size_t r : rows) {
    std::string failure;
    const auto v = numeric_cell(t, r, c, failure);
    ++res.checked_rows;
    if (!v) {
      res.failures.push_back(failure);
      continue;
    }
    const std::string head = run_label(t, r) + ": " + g.column + " = " + t.rows[r][c];
    const bool ok = is_max ? (g.strict ? *v < g.limit : *v <= g.limit)
                           : (g.strict ? *v > g.limit : *v >= g.limit);
    const double margin = is_max ? g.limit - *v : *v - g.limit;  // > 0 inside the limit
    const double excess = is_max ? *v - g.limit : g.limit - *v;  // >= 0 outside (no "-0")
    if (!ok) {
      if (std::isnan(*v))
        res.failures.push_back(head + ", not " + op_ok + " " + exact(g.limit));
      else
        res.failures.push_back(head + " " + op_bad + " " + exact(g.limit) + by_margin(excess, g.limit) +
                               (g.strict && margin == 0.0 ? " (the limit is strict)" : ""));
    } else if (margin < best_margin || worst.empty()) {
      best_margin = margin;
      worst = "closest " + head + " " + op_ok + " " + exact(g.limit) + " (margin " + approx(margin) +
              percent_of(margin, g.limit) + ")";
    }
  }
  if (res.failures.empty() && !worst.empty()) res.notes.push_back(worst);
}

void evaluate_near(const CsvTable& t, const Gate& g, const std::vector<std::size_t>& rows, std::size_t c,
                   GateResult& res) {
  const double abs_tol = g.tolerance.value_or(0.0);
  const double rel_tol = g.rel_tolerance ? *g.rel_tolerance * std::abs(g.reference) : 0.0;
  const double allowed = std::max(abs_tol, rel_tol);
  std::string how;
  if (g.rel_tolerance && (!g.tolerance || rel_tol >= abs_tol))
    how = "rel_tolerance " + exact(*g.rel_tolerance) + " x |reference|";
  else
    how = "tolerance";
  double worst_ratio = -1.0;
  std::string worst;
  for (const std::size_t r : rows) {
    std::string failure;
    const auto v = numeric_cell(t, r, c, failure);
    ++res.checked_rows;
    if (!v) {
      res.failures.push_back(failure);
      continue;
    }
    const double diff = *v - g.reference;
    const std::string head = run_label(t, r) + ": " + g.column + " = " + t.rows[r][c] + ", reference " +
                             exact(g.reference) + ": difference " + approx(diff) +
                             (g.reference != 0.0 && std::isfinite(diff)
                                  ? " (" + pct(100.0 * diff / std::abs(g.reference)) + " %)"
                                  : std::string());
    if (!(std::abs(diff) <= allowed)) {
      res.failures.push_back(head + " exceeds the allowed +-" + approx(allowed) + " (" + how + ")" +
                             (std::isfinite(diff) ? " by " + approx(std::abs(diff) - allowed) : ""));
    } else {
      const double ratio = allowed > 0 ? std::abs(diff) / allowed : 0.0;
      if (ratio > worst_ratio) {
        worst_ratio = ratio;
        worst = "farthest " + head + " within +-" + approx(allowed) + " (" + how + ")";
      }
    }
  }
  if (res.failures.empty() && !worst.empty()) res.notes.push_back(worst);
}

void evaluate_ratio(const CsvTable& t, const Gate& g, const std::vector<std::size_t>& rows, std::size_t c,
                    GateResult& res) {
  std::string f1, f2;
  const auto num = single_row(t, g.numerator, rows, "numerator", f1);
  const auto den = single_row(t, g.denominator, rows, "denominator", f2);
  if (!num) res.failures.push_back(f1);
  if (!den) res.failures.push_back(f2);
  if (!num || !den) return;
  res.checked_rows = 2;
  std::string fn, fd;
  const auto a = numeric_cell(t, *num, c, fn);
  const auto b = numeric_cell(t, *den, c, fd);
  if (!a) res.failures.push_back("numerator " + fn);
  if (!b) res.failures.push_back("denominator " + fd);
  if (!a || !b) return;
  const std::string head = g.column + " ratio " + run_label(t, *num) + " / " + run_label(t, *den) + " = " +
                           t.rows[*num][c] + " / " + t.rows[*den][c];
  if (*b == 0.0) {
    res.failures.push_back(head + ": the denominator is 0, the ratio is undefined");
    return;
  }
  const double q = *a / *b;
  const std::string shown = head + " = " + approx(q);
  bool ok = true;
  if (g.floor && !(q >= *g.floor)) {
    ok = false;
    res.failures.push_back(shown + " < floor " + exact(*g.floor) + by_margin(*g.floor - q, *g.floor));
  }
  if (g.ceiling && !(q <= *g.ceiling)) {
    ok = false;
    res.failures.push_back(shown + " > ceiling " + exact(*g.ceiling) + by_margin(q - *g.ceiling, *g.ceiling));
  }
  if (ok) {
    std::string note = shown;
    if (g.floor) note += " >= floor " + exact(*g.floor) + " (margin " + approx(q - *g.floor) + percent_of(q - *g.floor, *g.floor) + ")";
    if (g.ceiling) note += std::string(g.floor ? "," : "") + " <= ceiling " + exact(*g.ceiling) + " (margin " + approx(*g.ceiling - q) + percent_of(*g.ceiling - q, *g.ceiling) + ")";
    res.notes.push_back(note);
  }
}

void evaluate_count(const CsvTable& t, const Gate& g, const std::vector<std::size_t>& rows, GateResult& res) {
  const long n = static_cast<long>(rows.size());
  res.checked_rows = static_cast<int>(n);
  const std::string sel = std::to_string(n) + (n == 1 ? " row matches " : " rows match ") + describe_selector(g.where);
  const std::string which = rows.empty() ? "" : ": " + run_list(t, rows);
  if (g.min_rows && n < *g.min_rows)
    res.failures.push_back(sel + " < min " + std::to_string(*g.min_rows) + " (by " + std::to_string(*g.min_rows - n) + ")" + which);
  if (g.max_rows && n > *g.max_rows)
    res.failures.push_back(sel + " > max " + std::to_string(*g.max_rows) + " (by " + std::to_string(n - *g.max_rows) + ")" + which);
}

void evaluate_pattern(const CsvTable& t, const Gate& g, const std::vector<std::size_t>& rows, std::size_t c,
                      GateResult& res) {
  const auto reason_col = t.column_index("reason");
  for (const auto& cell : g.cells) {
    std::string failure;
    const auto r = single_row(t, cell.where, rows, "cell", failure);
    if (!r) {
      res.failures.push_back(failure);
      continue;
    }
    ++res.checked_rows;
    const std::string& got = t.rows[*r][c];
    if (got != cell.expect) {
      std::string f = "cell " + describe_selector(cell.where) + ": " + run_label(t, *r) + " " + g.column + " = " +
                      (got.empty() ? "(empty)" : got) + ", expected " + cell.expect;
      if (reason_col && *reason_col != c && !t.rows[*r][*reason_col].empty())
        f += " (reason: " + t.rows[*r][*reason_col] + ")";
      res.failures.push_back(f);
    }
  }
}

GateResult evaluate(const CsvTable& t, const Gate& g) {
  GateResult res;
  res.name = g.name;
  std::vector<std::size_t> all(t.rows.size());
  for (std::size_t r = 0; r < all.size(); ++r) all[r] = r;

  std::string error;
  const auto rows = select(t, g.where, all, "in where", error);
  std::optional<std::size_t> c;
  if (error.empty() && !g.column.empty()) {
    c = t.column_index(g.column);
    if (!c) error = missing_column(t, g.column, "the gate's column");
  }
  if (!error.empty()) {
    res.failures.push_back(error);
    return res;
  }

  const bool needs_rows = g.kind == GateKind::max || g.kind == GateKind::min || g.kind == GateKind::near;
  if (rows.empty() && g.kind != GateKind::count) {
    if (needs_rows && g.allow_empty) {
      res.passed = true;
      res.notes.push_back("no row matches where " + describe_selector(g.where) + " (allow_empty = true)");
      return res;
    }
    res.failures.push_back(
        "no row matches where " + describe_selector(g.where) + " in " + t.file + " (" +
        std::to_string(t.rows.size()) + " rows); a gate that selects nothing checks nothing" +
        (needs_rows ? " (set allow_empty = true if that is expected)" : ""));
    return res;
  }

  switch (g.kind) {
    case GateKind::max:
    case GateKind::min: evaluate_bound(t, g, rows, *c, res); break;
    case GateKind::near: evaluate_near(t, g, rows, *c, res); break;
    case GateKind::ratio: evaluate_ratio(t, g, rows, *c, res); break;
    case GateKind::count: evaluate_count(t, g, rows, res); break;
    case GateKind::pattern: evaluate_pattern(t, g, rows, *c, res); break;
  }
  res.passed = res.failures.empty();
  return res;
}

// ---------------------------------------------------------------------------------------------
// XML.

// Escapes text for XML 1.0 content or attribute values; bytes that are not valid UTF-8 and
// control characters XML forbids become '?'.
std::string xml_escape(std::string_view s, bool attribute) {
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size();) {
    const auto b = static_cast<unsigned char>(s[i]);
    if (b < 0x80) {
      const char c = static_cast<char>(b);
      switch (c) {
        case '&': out += "&amp;"; break;
        case '<': out += "&lt;"; break;
        case '>': out += "&gt;"; break;
        case '"': out += attribute ? "&quot;" : "\""; break;
        case '\'': out += attribute ? "&apos;" : "'"; break;
        case '\n': out += attribute ? "&#10;" : "\n"; break;
        case '\r': out += "&#13;"; break;
        case '\t': out += attribute ? "&#9;" : "\t"; break;
        default: out += b < 0x20 ? '?' : c;
      }
      ++i;
      continue;
    }
    // Multi-byte UTF-8: copy a well-formed sequence, replace anything else.
    const std::size_t len = (b & 0xE0) == 0xC0 ? 2 : (b & 0xF0) == 0xE0 ? 3 : (b & 0xF8) == 0xF0 ? 4 : 0;
    bool ok = len != 0 && i + len <= s.size() && b != 0xC0 && b != 0xC1 && b < 0xF5;
    for (std::size_t k = 1; ok && k < len; ++k) ok = (static_cast<unsigned char>(s[i + k]) & 0xC0) == 0x80;
    if (ok) {
      out.append(s.substr(i, len));
      i += len;
    } else {
      out += '?';
      ++i;
    }
  }
  return out;
}

std::string seconds(double t) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", std::isfinite(t) && t >= 0 ? t : 0.0);
  return buf;
}

std::string join(const std::vector<std::string>& v, const std::string& sep) {
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? sep : "") + v[i];
  return s;
}

}  // namespace

// -----------------------------------------------------------------------------------------------

namespace {

std::string read_text_file(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path.string() + ": cannot open gate file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open gate file");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Where each gate name was first seen: its file and index there.
struct NameSite {
  std::string file;
  std::size_t index = 0;
};

// Parses one gate file into gf: the gates of its `include` files first (recursively, paths
// relative to the including file), then its own. `stack` holds the files being read, for cycles.
void parse_into(std::string_view toml_text, const std::string& file, bool top, GateFile& gf,
                std::map<std::string, NameSite>& names, std::vector<fs::path>& stack) {
  const toml::table doc = parse_toml(toml_text, file);
  const CaseContext ctx{file, {}};
  const TableReader root(doc, "", ctx);
  const std::string name = root.text("name", fs::path(file).stem().string());
  if (name.empty()) root.fail("name", "expected a non-empty name");
  if (top) {
    gf.name = name;
    if (root.has("require_rows")) gf.require_rows = root.integer("require_rows", 0, 1, LONG_MAX);
  } else if (root.has("require_rows")) {
    root.fail("require_rows", "only the gate file given to the check sets require_rows, not an included one");
  }
  root.integer("require_rows", 0, 1, LONG_MAX);
  const std::vector<std::string> includes = root.texts("include");
  const auto gates = root.tables("gate");
  root.finish();

  for (const std::string& inc : includes) {
    const fs::path path = fs::path(file).parent_path() / inc;
    std::error_code ec;
    const fs::path key = fs::weakly_canonical(path, ec);
    if (std::find(stack.begin(), stack.end(), key) != stack.end())
      root.fail("include", "\"" + inc + "\" includes itself (an include cycle)");
    if (!fs::is_regular_file(path, ec)) root.fail("include", "cannot open gate file " + path.string());
    stack.push_back(key);
    parse_into(read_text_file(path), path.string(), false, gf, names, stack);
    stack.pop_back();
  }

  const toml::array* raw = gates.empty() ? nullptr : doc.get("gate")->as_array();
  for (std::size_t i = 0; i < gates.size(); ++i) {
    Gate g = read_gate(gates[i], *(*raw)[i].as_table(), i, ctx);
    if (g.name == "require_rows" && gf.require_rows)
      gates[i].fail("name", "\"require_rows\" is the name of the row-count check; choose another name");
    const auto [it, fresh] = names.emplace(g.name, NameSite{file, i});
    if (!fresh)
      gates[i].fail("name", "duplicate gate name \"" + g.name + "\" (also gate[" + std::to_string(it->second.index) + "]" +
                                (it->second.file == file ? "" : " of " + it->second.file) + ")");
    gf.gates.push_back(std::move(g));
  }
  if (top && gf.gates.empty() && !gf.require_rows)
    root.fail("gate", "no [[gate]] tables; a gate file must check something (docs/gates.md)");
}

}  // namespace

GateFile parse_gates(std::string_view toml_text, const std::string& file) {
  GateFile gf;
  gf.file = file;
  std::map<std::string, NameSite> names;
  std::error_code ec;
  std::vector<fs::path> stack{fs::weakly_canonical(fs::path(file), ec)};
  parse_into(toml_text, file, true, gf, names, stack);
  return gf;
}

GateFile read_gates(const fs::path& path) { return parse_gates(read_text_file(path), path.string()); }

std::vector<GateResult> evaluate_gates(const CsvTable& table, const GateFile& gates) {
  std::vector<GateResult> out;
  if (gates.require_rows) {
    GateResult r;
    r.name = "require_rows";
    const long n = static_cast<long>(table.rows.size());
    r.checked_rows = static_cast<int>(n);
    r.passed = n >= *gates.require_rows;
    if (!r.passed)
      r.failures.push_back(table.file + " has " + std::to_string(n) + " rows < require_rows " +
                           std::to_string(*gates.require_rows) + " (by " + std::to_string(*gates.require_rows - n) + ")");
    out.push_back(std::move(r));
  }
  for (const auto& g : gates.gates) out.push_back(evaluate(table, g));
  return out;
}

std::string describe(const GateResult& r) {
  if (r.passed) {
    std::string s = "PASS " + r.name + " (" + std::to_string(r.checked_rows) + (r.checked_rows == 1 ? " row)" : " rows)");
    for (const auto& n : r.notes) s += "; " + n;
    return s;
  }
  return "FAIL " + r.name + ": " + (r.failures.empty() ? std::string("failed") : join(r.failures, "; "));
}

std::string junit_xml(const std::vector<GateResult>& results, const std::string& suite, double elapsed_seconds) {
  std::size_t failed = 0;
  for (const auto& r : results) failed += r.passed ? 0 : 1;
  const std::string counts = " tests=\"" + std::to_string(results.size()) + "\" failures=\"" +
                             std::to_string(failed) + "\" errors=\"0\"";
  const std::string name = xml_escape(suite, true);
  std::string x = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  x += "<testsuites name=\"" + name + "\"" + counts + " time=\"" + seconds(elapsed_seconds) + "\">\n";
  x += "  <testsuite name=\"" + name + "\"" + counts + " skipped=\"0\" time=\"" + seconds(elapsed_seconds) + "\">\n";
  for (const auto& r : results) {
    x += "    <testcase classname=\"" + name + "\" name=\"" + xml_escape(r.name, true) + "\" time=\"0\"";
    if (r.passed && r.notes.empty()) {
      x += "/>\n";
      continue;
    }
    x += ">\n";
    if (!r.passed) {
      const std::vector<std::string> f = r.failures.empty() ? std::vector<std::string>{"failed"} : r.failures;
      x += "      <failure type=\"gate\" message=\"" + xml_escape(join(f, "; "), true) + "\">" +
           xml_escape(join(f, "\n"), false) + "</failure>\n";
    }
    if (!r.notes.empty()) x += "      <system-out>" + xml_escape(join(r.notes, "\n"), false) + "</system-out>\n";
    x += "    </testcase>\n";
  }
  x += "  </testsuite>\n</testsuites>\n";
  return x;
}

int run_gates(const CsvTable& table, const GateFile& gates, const fs::path& junit_path, std::ostream& out) {
  const auto results = check_gates(table, gates, junit_path, out);
  const bool passed = std::all_of(results.begin(), results.end(), [](const GateResult& r) { return r.passed; });
  return passed ? 0 : kGateFailedExit;
}

std::vector<GateResult> check_gates(const CsvTable& table, const GateFile& gates, const fs::path& junit_path,
                                    std::ostream& out) {
  const auto start = std::chrono::steady_clock::now();
  const auto results = evaluate_gates(table, gates);
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  int failed = 0;
  for (const auto& r : results) {
    out << describe(r) << '\n';
    failed += r.passed ? 0 : 1;
  }
  out << "gates: " << (static_cast<int>(results.size()) - failed) << " passed, " << failed << " failed\n";
  out.flush();
  write_file_atomic(junit_path, junit_xml(results, gates.name, elapsed));
  return results;
}

std::string gate_detail(const GateResult& r) {
  if (!r.passed) return r.failures.empty() ? std::string("failed") : join(r.failures, "; ");
  std::string s = std::to_string(r.checked_rows) + (r.checked_rows == 1 ? " row" : " rows");
  for (const auto& n : r.notes) s += "; " + n;
  return s;
}

int run_command(const CheckCommand& c, std::ostream& out) {
  const CsvTable table = read_csv(c.summary_csv);
  const GateFile gates = read_gates(c.gates_toml);
  const fs::path junit_path = c.junit.empty() ? fs::path(c.summary_csv).parent_path() / "gates-junit.xml" : fs::path(c.junit);
  // Once both inputs are read, whatever fails (e.g. writing the JUnit file) is not bad input.
  try {
    return run_gates(table, gates, junit_path, out);
  } catch (const std::exception& e) {
    throw std::runtime_error(e.what());
  }
}

}  // namespace ricochet
