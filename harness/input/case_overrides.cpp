// --set KEY=VALUE: edits the parsed case document before validation, so an override is
// checked exactly like the file's own keys.
#include <cctype>

#include "harness/input/case_spec.hpp"
#include "harness/input/input_error.hpp"

namespace ricochet {
namespace {

bool is_index(const std::string& s) {
  if (s.empty() || s.size() > 6) return false;
  for (char c : s)
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
  return true;
}

}  // namespace

std::vector<std::string> split_key(const std::string& key) {
  std::vector<std::string> parts;
  std::string cur;
  for (char ch : key) {
    if (ch == '.' || ch == '[' || ch == ']') {
      if (!cur.empty()) parts.push_back(cur);
      cur.clear();
    } else {
      cur += ch;
    }
  }
  if (!cur.empty()) parts.push_back(cur);
  return parts;
}

std::string apply_override(toml::table& doc, const std::string& file, const std::string& arg) {
  const std::string context = file + ": --set " + arg + ": ";
  const auto eq = arg.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError(context + "expected KEY=VALUE, e.g. time.dt=1e-6");
  const std::string key = arg.substr(0, eq);
  const std::string value = arg.substr(eq + 1);
  const std::vector<std::string> parts = split_key(key);
  for (const auto& p : parts)
    for (char c : p)
      if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-'))
        throw InputError(context + "bad key; keys are words joined by '.', array elements as [N]");
  if (parts.empty() || is_index(parts.front()) || is_index(parts.back()))
    throw InputError(context + "bad key; it must start and end with a key name");

  // The value in TOML syntax (numbers, booleans, "strings", [arrays], {inline tables}); a bare
  // word that is not TOML is taken as a string, so mesh=M2 works.
  toml::table parsed;
  try {
    parsed = toml::parse("v = " + value);
  } catch (const toml::parse_error&) {
    parsed.insert("v", value);
  }
  if (value.empty()) throw InputError(context + "empty value");

  std::string canonical;
  toml::node* cur = &doc;
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    const std::string& p = parts[i];
    if (toml::array* a = cur->as_array()) {
      if (!is_index(p)) throw InputError(context + "'" + canonical + "' is an array; index it as [N]");
      const std::size_t idx = std::stoul(p);
      if (idx >= a->size())
        throw InputError(context + "'" + canonical + "' has " + std::to_string(a->size()) + " elements");
      canonical += "[" + p + "]";
      cur = a->get(idx);
      continue;
    }
    toml::table* t = cur->as_table();
    if (!t || is_index(p))
      throw InputError(context + "'" + (canonical.empty() ? p : canonical) + "' is not a table");
    canonical += (canonical.empty() ? "" : ".") + p;
    if (!t->contains(p)) t->insert(p, toml::table{});
    cur = t->get(p);
  }
  toml::table* t = cur->as_table();
  if (!t) throw InputError(context + "'" + canonical + "' is not a table");
  canonical += (canonical.empty() ? "" : ".") + parts.back();
  t->insert_or_assign(parts.back(), *parsed.get("v"));
  return canonical;
}

}  // namespace ricochet
