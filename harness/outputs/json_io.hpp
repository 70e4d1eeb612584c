// JSON for the harness's outputs (summary.json, sweep.json, stability.json, overrides.json) and
// for reading them back (the sweep driver reads each run's summary.json): nlohmann::json with
// the keys of every object in insertion order, written in one format by dump_json.
//
//   Json doc = Json::object();
//   doc["case"] = "taylor_bar";
//   doc["energy"]["kinetic_J"] = 12.5;   // a null member becomes an object on first use
//   doc["steps"].push_back(1);           // ... or an array
//   write_file_atomic(dir / "summary.json", dump_json(doc));
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace ricochet {

// Objects keep their keys in insertion order (a parsed document: in document order).
using Json = nlohmann::ordered_json;

struct JsonParseError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The document as every JSON output of the harness is written: two-space indentation, one
// member or element per line, "key": value, empty containers as {} and [], and a trailing
// newline. Integers as integers; doubles in shortest round-trip form, always with a '.' or an
// exponent (2.0, 1e-07), so that they parse back to the same double and stay doubles; NaN and
// +-inf as null. Strings are UTF-8, written unchanged except for the escapes JSON requires
// (a byte sequence that is not UTF-8 is written as U+FFFD).
std::string dump_json(const Json& doc);

// Parses a whole document (RFC 8259: one value, optional surrounding whitespace). Throws
// JsonParseError "parse error at line L, column C: what" (one line).
Json parse_json(std::string_view text);

// Reads and parses a file. Throws JsonParseError "FILE: cannot read" or "FILE: <parse error>".
Json read_json_file(const std::filesystem::path& path);

// A value as one line of text, as summary.csv shows it: strings in JSON quotes, numbers as
// append_number (csv_writer.hpp) writes them (a double that holds an integer without a '.':
// "2", "1e-07"; integers as integers), arrays and objects as compact JSON (no whitespace, keys
// in order) of such values.
std::string compact_json(const Json& value);

}  // namespace ricochet
