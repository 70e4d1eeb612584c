#include "harness/json_writer.hpp"

#include <charconv>
#include <cmath>

#include "harness/csv_writer.hpp"

namespace ricochet {
namespace {

// A JSON string literal: '"' and '\' escaped with a backslash, control characters U+0000 to
// U+001F as \u00XX; every other byte (including UTF-8 sequences) unchanged.
void append_string(std::string& out, std::string_view text) {
  static constexpr char hex[] = "0123456789abcdef";
  out += '"';
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (byte < 0x20) {
      out += "\\u00";
      out += hex[byte >> 4];
      out += hex[byte & 0xF];
    } else {
      out += c;
    }
  }
  out += '"';
}

void append_newline(std::string& out, int indent) {
  out += '\n';
  out.append(static_cast<std::size_t>(indent) * 2, ' ');
}

}  // namespace

Json Json::object() {
  Json json;
  json.value_ = Object{};
  return json;
}

Json Json::array() {
  Json json;
  json.value_ = Array{};
  return json;
}

std::size_t Json::size() const {
  if (const auto* object = std::get_if<Object>(&value_)) return object->size();
  if (const auto* array = std::get_if<Array>(&value_)) return array->size();
  return 0;
}

Json& Json::operator[](std::string_view key) {
  if (is_null()) value_ = Object{};
  auto* object = std::get_if<Object>(&value_);
  if (object == nullptr) {
    throw std::logic_error("Json: operator[] on a value that is not an object");
  }
  for (auto& [name, member] : *object) {
    if (name == key) return member;
  }
  return object->emplace_back(std::string(key), Json()).second;
}

Json& Json::push_back(Json value) {
  if (is_null()) value_ = Array{};
  auto* array = std::get_if<Array>(&value_);
  if (array == nullptr) {
    throw std::logic_error("Json: push_back on a value that is not an array");
  }
  return array->emplace_back(std::move(value));
}

std::string Json::dump() const {
  std::string out;
  dump_to(out, 0);
  out += '\n';
  return out;
}

void Json::dump_to(std::string& out, int indent) const {
  if (is_null()) {
    out += "null";
  } else if (const auto* b = std::get_if<bool>(&value_)) {
    out += *b ? "true" : "false";
  } else if (const auto* i = std::get_if<std::int64_t>(&value_)) {
    char buffer[24];
    out.append(buffer, std::to_chars(buffer, buffer + sizeof buffer, *i).ptr);
  } else if (const auto* d = std::get_if<double>(&value_)) {
    if (std::isfinite(*d)) {
      append_number(out, *d);
    } else {
      out += "null";
    }
  } else if (const auto* s = std::get_if<std::string>(&value_)) {
    append_string(out, *s);
  } else if (const auto* array = std::get_if<Array>(&value_)) {
    out += '[';
    for (std::size_t k = 0; k < array->size(); ++k) {
      if (k > 0) out += ',';
      append_newline(out, indent + 1);
      (*array)[k].dump_to(out, indent + 1);
    }
    if (!array->empty()) append_newline(out, indent);
    out += ']';
  } else {
    const auto& object = std::get<Object>(value_);
    out += '{';
    for (std::size_t k = 0; k < object.size(); ++k) {
      if (k > 0) out += ',';
      append_newline(out, indent + 1);
      append_string(out, object[k].first);
      out += ": ";
      object[k].second.dump_to(out, indent + 1);
    }
    if (!object.empty()) append_newline(out, indent);
    out += '}';
  }
}

}  // namespace ricochet
