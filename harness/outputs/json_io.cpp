#include "harness/outputs/json_io.hpp"

#include <fstream>
#include <sstream>

#include "harness/outputs/csv_writer.hpp"

namespace ricochet {
namespace {

// nlohmann's message without its "[json.exception.parse_error.101] " prefix.
std::string without_id(const nlohmann::json::exception& e) {
  const std::string what = e.what();
  const auto close = what.rfind("] ", what.find(' '));
  return what.rfind("[json.exception.", 0) == 0 && close != std::string::npos ? what.substr(close + 2) : what;
}

void compact_to(const Json& v, std::string& out) {
  if (v.is_number_float()) {
    append_number(out, v.get<double>());
  } else if (v.is_array()) {
    out += '[';
    for (std::size_t i = 0; i < v.size(); ++i) {
      if (i > 0) out += ',';
      compact_to(v[i], out);
    }
    out += ']';
  } else if (v.is_object()) {
    out += '{';
    bool first = true;
    for (const auto& [key, member] : v.items()) {
      if (!first) out += ',';
      first = false;
      out += Json(key).dump(-1, ' ', false, Json::error_handler_t::replace);
      out += ':';
      compact_to(member, out);
    }
    out += '}';
  } else {
    out += v.dump(-1, ' ', false, Json::error_handler_t::replace);
  }
}

}  // namespace

std::string dump_json(const Json& doc) {
  return doc.dump(2, ' ', false, Json::error_handler_t::replace) + '\n';
}

Json parse_json(std::string_view text) {
  try {
    return Json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw JsonParseError(without_id(e));
  }
}

Json read_json_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw JsonParseError(path.string() + ": cannot read");
  std::ostringstream buf;
  buf << in.rdbuf();
  if (in.bad()) throw JsonParseError(path.string() + ": cannot read");
  try {
    return parse_json(buf.str());
  } catch (const JsonParseError& e) {
    throw JsonParseError(path.string() + ": " + e.what());
  }
}

std::string compact_json(const Json& value) {
  std::string out;
  compact_to(value, out);
  return out;
}

}  // namespace ricochet
