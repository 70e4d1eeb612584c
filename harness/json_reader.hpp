// A small, strict JSON reader (RFC 8259) for the harness's own outputs: the sweep driver reads
// each run's summary.json with it. It keeps every number's source text, so a value can be
// copied to a table exactly as the writer wrote it.
#pragma once

#include <cstddef>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace ricochet {

struct JsonParseError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct JsonValue {
  enum class Kind { null, boolean, number, string, array, object };

  Kind kind = Kind::null;
  bool boolean = false;
  double number = 0.0;  // kind == number: the value (strtod of `text`)
  std::string text;     // kind == string: the decoded UTF-8 text; kind == number: the source text
  std::vector<JsonValue> items;                             // kind == array
  std::vector<std::pair<std::string, JsonValue>> members;  // kind == object, in document order

  bool is_null() const { return kind == Kind::null; }
  bool is_number() const { return kind == Kind::number; }
  bool is_string() const { return kind == Kind::string; }
  bool is_object() const { return kind == Kind::object; }
  bool is_array() const { return kind == Kind::array; }

  // The member `key` of an object (the last one if repeated); nullptr if absent or not an object.
  const JsonValue* find(std::string_view key) const;
  // Compact JSON text: no whitespace, numbers as in the source, strings re-escaped.
  std::string compact() const;
};

// Parses a whole document (one value, surrounded by optional whitespace). Accepts objects,
// arrays, strings with every escape (\uXXXX with surrogate pairs becomes UTF-8), numbers in JSON
// syntax, true, false and null; rejects anything else, including trailing text, control
// characters inside strings and nesting deeper than 256. Throws JsonParseError
// "line L, column C: what".
JsonValue parse_json(std::string_view text);

// Reads and parses a file. Throws JsonParseError "FILE: ..." (cannot read, or parse error).
JsonValue read_json_file(const std::filesystem::path& path);

// `text` as a JSON string literal, quotes included.
std::string json_quote(std::string_view text);

}  // namespace ricochet
