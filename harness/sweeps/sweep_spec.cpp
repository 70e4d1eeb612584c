#include "harness/sweeps/sweep_spec.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <map>
#include <set>

#include "harness/input/case_spec.hpp"
#include "harness/outputs/csv_writer.hpp"
#include "harness/input/input_error.hpp"
#include "harness/input/toml_reader.hpp"

namespace ricochet {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kMaxRuns = 100'000;
constexpr std::size_t kMaxSlug = 120;

bool is_bare_key(std::string_view k) {
  if (k.empty()) return false;
  for (char c : k)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) return false;
  return true;
}

bool all_digits(std::string_view s) {
  if (s.empty()) return false;
  for (char c : s)
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
  return true;
}

std::string toml_string(std::string_view s) {
  std::string out = "\"";
  for (const char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      case '\b': out += "\\b"; break;
      case '\f': out += "\\f"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04X", static_cast<unsigned>(static_cast<unsigned char>(c)));
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

// Shortest round-trip text with a short exponent: 1e-05 -> 1e-5, 1e+20 -> 1e20; a float that
// would read back as an integer gets ".0".
std::string float_text(double x) {
  std::string s;
  append_number(s, x);
  const auto e = s.find('e');
  if (e != std::string::npos) {
    std::string mant = s.substr(0, e), exp = s.substr(e + 1);
    std::string sign;
    if (!exp.empty() && (exp[0] == '+' || exp[0] == '-')) {
      if (exp[0] == '-') sign = "-";
      exp.erase(0, 1);
    }
    const auto nz = exp.find_first_not_of('0');
    exp = nz == std::string::npos ? "0" : exp.substr(nz);
    s = mant + "e" + sign + exp;
  }
  if (s.find_first_of(".en") == std::string::npos) s += ".0";  // nan, inf contain 'n'
  return s;
}

struct Leaf {
  std::string key;          // dotted path as written (prefix + key)
  const toml::node* value;  // the value
  TableReader reader;       // the table that holds it, for messages
  std::string local;        // its key in that table
  toml::source_position pos;
};

bool before(const toml::source_position& a, const toml::source_position& b) {
  return a.line != b.line ? a.line < b.line : a.column < b.column;
}

// The leaves of a table of case keys, nested tables flattened into dotted keys, in the order
// they are written in the file.
void collect(const toml::table& t, const TableReader& r, const std::string& prefix, std::vector<Leaf>& out) {
  for (auto&& [k, v] : t) {
    const std::string key(k.str());
    if (const toml::table* sub = v.as_table()) {
      const auto sr = r.table(key);
      collect(*sub, *sr, prefix + key + ".", out);
    } else {
      out.push_back(Leaf{prefix + key, &v, r, key, k.source().begin});
    }
  }
}

std::vector<Leaf> leaves(const toml::table& t, const TableReader& r) {
  std::vector<Leaf> out;
  collect(t, r, "", out);
  std::stable_sort(out.begin(), out.end(), [](const Leaf& a, const Leaf& b) { return before(a.pos, b.pos); });
  return out;
}

std::string where_of(const std::string& file, const Leaf& l) {
  const auto line = l.value->source().begin.line;
  return file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " + l.reader.key_path(l.local);
}

// Checks a leaf's key and returns its canonical form; rejects a key given twice.
std::string checked_key(const Leaf& l, std::set<std::string>& seen) {
  for (char c : l.key)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' || c == '[' || c == ']'))
      l.reader.fail(l.local, "bad case key; keys are words joined by '.', array elements as [N]");
  const std::string key = canonical_key(l.key);
  if (key.empty() || key.front() == '[' || key.back() == ']')
    l.reader.fail(l.local, "bad case key; it must start and end with a key name");
  if (!seen.insert(key).second) l.reader.fail(l.local, "the case key '" + key + "' is given twice");
  return key;
}

SweepValue make_value(const std::string& file, const Leaf& l, const std::string& key, const toml::node& v) {
  SweepValue sv;
  sv.key = key;
  try {
    sv.toml = toml_text(v);
    sv.display = display_text(v);
  } catch (const InputError& e) {
    l.reader.fail(l.local, e.what());
  }
  sv.where = where_of(file, l);
  return sv;
}

// `set = { KEY = VALUE, ... }` or `reference = { ... }`: single values.
std::vector<SweepValue> read_values(const std::string& file, const TableReader& parent, const toml::table& doc,
                                    const char* name) {
  std::vector<SweepValue> out;
  const auto r = parent.table(name);
  if (!r) return out;
  std::set<std::string> seen;
  for (const Leaf& l : leaves(*doc.get(name)->as_table(), *r)) {
    const std::string key = checked_key(l, seen);
    out.push_back(make_value(file, l, key, *l.value));
  }
  return out;
}

std::vector<SweepAxis> read_cross(const std::string& file, const TableReader& parent, const toml::table& doc) {
  std::vector<SweepAxis> out;
  const auto r = parent.table("cross");
  if (!r) return out;
  std::set<std::string> seen;
  for (const Leaf& l : leaves(*doc.get("cross")->as_table(), *r)) {
    const std::string key = checked_key(l, seen);
    const toml::array* a = l.value->as_array();
    if (!a) l.reader.fail(l.local, "expected a list of values to cross, e.g. [1e-4, 1e-5]");
    if (a->empty()) l.reader.fail(l.local, "empty list; give at least one value");
    SweepAxis axis;
    axis.key = key;
    std::set<std::string> values;
    for (const toml::node& e : *a) {
      SweepValue v = make_value(file, l, key, e);
      if (!values.insert(v.toml).second) l.reader.fail(l.local, "the value " + v.toml + " is listed twice");
      axis.values.push_back(std::move(v));
    }
    out.push_back(std::move(axis));
  }
  return out;
}

// The optional `base` of a table (the sweep's or a group's): a case file, resolved against the
// sweep file's folder so that a sweep runs the same from any working directory; empty if absent.
fs::path read_base(const std::string& file, const TableReader& r) {
  fs::path p = r.text("base", std::string());  // marks `base` as allowed for finish()'s message
  if (!r.has("base")) return {};
  if (p.is_relative()) p = fs::path(file).parent_path() / p;
  p = p.lexically_normal();
  if (!fs::is_regular_file(p)) r.fail("base", "case file '" + p.string() + "' not found");
  return p;
}

void merge(std::vector<SweepValue>& into, const std::vector<SweepValue>& values) {
  for (const SweepValue& v : values) {
    std::erase_if(into, [&](const SweepValue& o) { return o.key == v.key; });
    into.push_back(v);
  }
}

std::string slug_part(std::string_view s, bool key) {
  std::string out;
  for (char c : s) {
    if (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '=' || c == '-') {
      out += c;
    } else if (key && c == '[') {
      out += '.';
    } else if (key && c == ']') {
    } else if (out.empty() || out.back() != '_') {
      out += '_';
    }
  }
  while (!out.empty() && out.front() == '_') out.erase(0, 1);
  while (!out.empty() && out.back() == '_') out.pop_back();
  return out;
}

std::string index3(std::size_t i) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "%03zu", i);
  return buf;
}

// The top-level [reference] table (the sweep's `base` and `set` already read).
SweepReference read_reference(const std::string& file, const TableReader& root, const toml::table& doc,
                              const SweepSpec& s) {
  SweepReference ref;
  const auto r = root.table("reference");
  if (!r) return ref;
  ref.present = true;
  const toml::table& t = *doc.get("reference")->as_table();
  const auto line = t.source().begin.line;
  ref.where = file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": reference";
  ref.name = r->text("name", ref.name);
  if (!valid_name(ref.name))
    r->fail("name", "\"" + ref.name + "\": allowed: letters, digits, '_', '-', '.' (not first); at most 64 characters");
  ref.base = read_base(file, *r);
  if (ref.base.empty() && s.base.empty())
    r->fail("base", "missing: the sweep has no top-level `base`, so [reference] must name its own case file");
  ref.set = read_values(file, *r, t, "set");
  if (ref.set.empty())
    r->fail("set", std::string(r->has("set") ? "empty table" : "missing") +
                       ": give the case keys of the reference run, e.g. set = { mesh = \"M2\", \"time.dt\" = 1e-7 }");
  ref.check = read_values(file, *r, t, "check");
  if (r->has("check")) {
    if (ref.check.empty())
      r->fail("check", "empty table; give the case keys in which the check run differs from the reference, "
                       "e.g. check = { scheme = \"implicit\" }");
    std::vector<SweepValue> merged = s.set;
    merge(merged, ref.set);
    const bool changes = std::any_of(ref.check.begin(), ref.check.end(), [&](const SweepValue& v) {
      return std::none_of(merged.begin(), merged.end(),
                          [&](const SweepValue& o) { return o.key == v.key && o.toml == v.toml; });
    });
    if (!changes)
      r->fail("check", "the check run would be the reference run itself: each of its values is already the reference's");
  }
  ref.error_probe = r->text("error_probe", ref.error_probe);
  if (!is_bare_key(ref.error_probe) || ref.error_probe.find('-') != std::string::npos)
    r->fail("error_probe", "\"" + ref.error_probe + "\": a probe name is letters, digits and '_'");
  r->finish();
  return ref;
}

// The search options of a stability group, as `ricochet stability` takes them (same names, with
// '_' for '-', and the same ranges, so that a bad value stops the sweep before any run instead
// of failing each search); the ones given, in the order of the command's help.
std::vector<SweepStabilityOption> read_stability_options(const TableReader& g) {
  std::vector<SweepStabilityOption> out;
  auto number = [&](const char* key, const char* flag, Range r) {
    if (!g.has(key)) return;
    out.push_back({key, flag, float_text(g.number(key, r))});  // Range: finite numbers only
  };
  number("tolerance", "--tolerance", Range{0.0, 10.0, true, false});
  if (g.has("max_runs")) out.push_back({"max_runs", "--max-runs", std::to_string(g.integer("max_runs", 30, 1, 10000))});
  number("end", "--end", Range::positive());
  number("energy_bound", "--energy-bound", Range::positive());
  return out;
}

constexpr const char* kStabilityKeys[] = {"tolerance", "max_runs", "end", "energy_bound"};

}  // namespace

bool valid_name(const std::string& s) {
  if (s.empty() || s.size() > 64 || s[0] == '.' || s[0] == '-') return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) return false;
  return true;
}

std::string toml_text(const toml::node& v) {
  switch (v.type()) {
    case toml::node_type::string: return toml_string(v.as_string()->get());
    case toml::node_type::integer: return std::to_string(v.as_integer()->get());
    case toml::node_type::floating_point: return float_text(v.as_floating_point()->get());
    case toml::node_type::boolean: return v.as_boolean()->get() ? "true" : "false";
    case toml::node_type::array: {
      std::string s = "[";
      bool first = true;
      for (const toml::node& e : *v.as_array()) {
        s += first ? "" : ", ";
        first = false;
        s += toml_text(e);
      }
      return s + "]";
    }
    case toml::node_type::table: {
      const toml::table& t = *v.as_table();
      if (t.empty()) return "{}";
      std::string s = "{ ";
      bool first = true;
      for (auto&& [k, e] : t) {
        s += first ? "" : ", ";
        first = false;
        s += is_bare_key(k.str()) ? std::string(k.str()) : toml_string(k.str());
        s += " = " + toml_text(e);
      }
      return s + " }";
    }
    default: throw InputError("dates and times are not case values");
  }
}

std::string display_text(const toml::node& v) {
  if (const auto* t = v.as_string()) return t->get();
  return toml_text(v);
}

std::string canonical_key(const std::string& key) {
  const std::vector<std::string> parts = split_key(key);
  std::string out;
  for (const auto& p : parts) {
    if (all_digits(p)) out += "[" + p + "]";
    else out += (out.empty() ? "" : ".") + p;
  }
  return out;
}

std::string slug(const std::vector<SweepValue>& values) {
  std::string out;
  for (const SweepValue& v : values) {
    const std::string part = slug_part(v.key, true) + "=" + slug_part(v.display, false);
    out += (out.empty() ? "" : "_") + part;
  }
  if (out.size() > kMaxSlug) out.resize(kMaxSlug);
  return out;
}

std::vector<std::string> SweepRun::set_args() const {
  std::vector<std::string> out;
  for (const SweepValue& v : overrides) out.push_back(v.set_arg());
  return out;
}

std::filesystem::path SweepRun::folder() const { return fs::path("runs") / fs::path(id); }

SweepSpec read_sweep(const std::string& file) {
  const toml::table doc = parse_toml_file(file, "sweep file");
  const CaseContext ctx{file, {}};
  const TableReader root(doc, "", ctx);
  SweepSpec s;
  s.file = file;
  s.name = root.text("name", fs::path(file).stem().string());
  if (!valid_name(s.name)) root.fail("name", "\"" + s.name + "\": allowed: letters, digits, '_', '-', '.'; at most 64 characters");
  s.description = root.text("description", "");
  s.base = read_base(file, root);
  s.set = read_values(file, root, doc, "set");
  s.reference = read_reference(file, root, doc, s);

  const auto groups = root.tables("group");
  if (groups.empty()) root.fail("group", "missing: give at least one [[group]] with the lists to cross");
  const toml::array& garr = *doc.get("group")->as_array();
  std::map<std::string, std::string> names;
  for (std::size_t i = 0; i < groups.size(); ++i) {
    const TableReader& g = groups[i];
    const toml::table& gt = *garr[i].as_table();
    SweepGroup sg;
    const auto line = gt.source().begin.line;
    sg.where = file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " + g.path();
    sg.name = g.text("name", "group" + std::to_string(i));
    if (!valid_name(sg.name))
      g.fail("name", "\"" + sg.name + "\": allowed: letters, digits, '_', '-', '.' (not first); at most 64 characters");
    if (s.reference.present && sg.name == "reference")
      g.fail("name", "\"reference\" is taken by the runs of the sweep's [reference] (reference/" + s.reference.name +
                         "); choose another name");
    if (const auto [it, fresh] = names.emplace(sg.name, g.path()); !fresh)
      g.fail("name", "\"" + sg.name + "\" is already the name of " + it->second);
    sg.description = g.text("description", "");
    sg.stability = g.choice("kind", "run", {"run", "stability"}) == "stability";
    if (sg.stability) {
      if (g.has("reference"))
        g.fail("reference", "a stability group (kind = \"stability\") has no reference: its searches are compared "
                            "with the estimate, not with a run; remove `reference`");
      sg.stability_options = read_stability_options(g);
    } else {
      for (const char* key : kStabilityKeys)
        if (g.has(key))
          g.fail(key, "a search option, only for a stability group; add kind = \"stability\" or remove it");
    }
    sg.base = read_base(file, g);
    if (sg.base.empty() && s.base.empty())
      g.fail("base", "missing: the sweep has no top-level `base`, so every group must name its own case file");
    sg.set = read_values(file, g, gt, "set");
    sg.cross = read_cross(file, g, gt);
    if (const toml::node* n = gt.get("reference"); n && !n->is_table()) {
      if (const auto* b = n->as_boolean(); !b || b->get())
        g.fail("reference", "expected a table of case keys (the group's own reference runs), or false (not compared "
                            "with the sweep's [reference]); got " + (n->is_boolean() ? std::string("true") : type_name(*n)));
      g.boolean("reference", false);
      if (!s.reference.present) g.fail("reference", "`false` opts out of the sweep's [reference], and this sweep has none");
      sg.reference_opt_out = true;
    } else {
      sg.reference = read_values(file, g, gt, "reference");
      if (g.has("reference") && sg.reference.empty()) g.fail("reference", "empty table; give the keys of the reference run");
    }
    sg.error_probe = g.text("error_probe", "P");
    if (!is_bare_key(sg.error_probe) || sg.error_probe.find('-') != std::string::npos)
      g.fail("error_probe", "\"" + sg.error_probe + "\": a probe name is letters, digits and '_'");
    if (g.has("error_probe") && sg.stability)
      g.fail("error_probe", "not used by a stability group: its searches measure no errors; remove it");
    if (g.has("error_probe") && sg.reference.empty())
      g.fail("error_probe", s.reference.present
                                ? "only used with the group's own `reference` table; the groups compared with the "
                                  "sweep's [reference] use its error_probe"
                                : "only used with `reference`; this group has none");
    g.finish();
    s.groups.push_back(std::move(sg));
  }
  root.finish();
  if (s.reference.present &&
      std::none_of(s.groups.begin(), s.groups.end(),
                   [](const SweepGroup& g) { return g.reference.empty() && !g.reference_opt_out && !g.stability; }))
    throw InputError(s.reference.where + ": no group is compared with it: every group has its own `reference`, "
                     "`reference = false` or kind = \"stability\"; remove [reference], or a group's `reference`");
  return s;
}

std::vector<SweepRun> expand(const SweepSpec& spec) {
  std::size_t total = 0;
  for (const SweepGroup& g : spec.groups) {
    std::size_t n = 1;
    for (const SweepAxis& a : g.cross) {
      n *= a.values.size();
      if (n > kMaxRuns) break;
    }
    total += n;
    if (total > kMaxRuns) break;
  }
  if (spec.reference.present) total += spec.reference.check.empty() ? 1 : 2;
  if (total > kMaxRuns)
    throw InputError(spec.file + ": the sweep expands to more than " + std::to_string(kMaxRuns) + " runs");

  std::vector<SweepRun> out;
  const SweepReference& shared = spec.reference;
  if (shared.present) {
    SweepRun r;
    r.id = shared.id();
    r.group = "reference";
    r.base = shared.base.empty() ? spec.base : shared.base;
    if (r.base.empty()) throw InputError(shared.where + ".base: missing, and the sweep has no top-level `base`");
    r.is_reference = true;
    r.overrides = spec.set;
    merge(r.overrides, shared.set);
    for (const SweepValue& v : shared.set) r.swept.push_back(v.key);
    r.error_probe = shared.error_probe;
    out.push_back(r);
    if (!shared.check.empty()) {
      SweepRun c = r;
      c.id = shared.check_id();
      merge(c.overrides, shared.check);
      for (const SweepValue& v : shared.check)
        if (std::find(c.swept.begin(), c.swept.end(), v.key) == c.swept.end()) c.swept.push_back(v.key);
      c.reference_id = r.id;
      c.reference_kind = "shared";
      out.push_back(std::move(c));
    }
  }
  for (const SweepGroup& g : spec.groups) {
    const fs::path case_file = g.base.empty() ? spec.base : g.base;
    if (case_file.empty()) throw InputError(g.where + ".base: missing, and the sweep has no top-level `base`");
    std::vector<SweepValue> base = spec.set;
    merge(base, g.set);

    // Every combination, first axis slowest.
    std::vector<std::vector<SweepValue>> combos;
    std::vector<std::size_t> at(g.cross.size(), 0);
    for (;;) {
      std::vector<SweepValue> c;
      for (std::size_t a = 0; a < g.cross.size(); ++a) c.push_back(g.cross[a].values[at[a]]);
      combos.push_back(std::move(c));
      bool done = true;
      for (std::size_t a = g.cross.size(); a-- > 0;) {
        if (++at[a] < g.cross[a].values.size()) {
          done = false;
          break;
        }
        at[a] = 0;
      }
      if (done) break;
    }

    std::set<std::string> ref_keys;
    for (const SweepValue& v : g.reference) ref_keys.insert(v.key);
    std::map<std::string, std::string> ref_of;  // combination of non-reference values -> reference id
    auto free_part = [&](const std::vector<SweepValue>& c) {
      std::vector<SweepValue> f;
      for (const SweepValue& v : c)
        if (!ref_keys.count(v.key)) f.push_back(v);
      return f;
    };
    auto signature = [](const std::vector<SweepValue>& f) {
      std::string s;
      for (const SweepValue& v : f) s += v.key + "=" + v.toml + "\n";
      return s;
    };

    if (!g.reference.empty()) {
      for (const auto& c : combos) {
        const std::vector<SweepValue> f = free_part(c);
        const std::string sig = signature(f);
        if (ref_of.count(sig)) continue;
        SweepRun r;
        r.group = g.name;
        r.base = case_file;
        r.is_reference = true;
        std::vector<SweepValue> named = f;
        named.insert(named.end(), g.reference.begin(), g.reference.end());
        const std::string sl = slug(named);
        r.id = g.name + "/reference" + (sl.empty() ? "" : "-" + sl);
        r.overrides = base;
        merge(r.overrides, f);
        merge(r.overrides, g.reference);
        for (const SweepValue& v : named) r.swept.push_back(v.key);
        r.error_probe = g.error_probe;
        ref_of.emplace(sig, r.id);
        out.push_back(std::move(r));
      }
    }
    for (std::size_t i = 0; i < combos.size(); ++i) {
      SweepRun r;
      r.group = g.name;
      r.base = case_file;
      const std::string sl = slug(combos[i]);
      r.id = g.name + "/" + index3(i) + (sl.empty() ? "" : "-" + sl);
      r.overrides = base;
      merge(r.overrides, combos[i]);
      for (const SweepValue& v : combos[i]) r.swept.push_back(v.key);
      if (g.stability) {
        r.stability = true;
        r.stability_options = g.stability_options;
      } else if (!g.reference.empty()) {
        r.reference_id = ref_of.at(signature(free_part(combos[i])));
        r.reference_kind = "group";
        r.error_probe = g.error_probe;
      } else if (shared.present && !g.reference_opt_out) {
        r.reference_id = shared.id();
        r.reference_kind = "shared";
        r.error_probe = shared.error_probe;
      }
      out.push_back(std::move(r));
    }
  }
  return out;
}

}  // namespace ricochet
