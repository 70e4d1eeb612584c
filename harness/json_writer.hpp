// A small JSON document builder for the harness's outputs (summary.json and similar). It only
// writes JSON; it never parses it.
#pragma once

#include <concepts>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace ricochet {

// A JSON value: null, boolean, integer (int64), number (double), string, array or object.
// Objects keep their keys in insertion order and never hold a key twice.
//
//   Json doc = Json::object();
//   doc["case"] = "taylor_bar";
//   doc["energy"]["kinetic_J"] = 12.5;   // a null member becomes an object on first use
//   doc["steps"].push_back(1);           // ... or an array
//   write_file_atomic(dir / "summary.json", doc.dump());
class Json {
 public:
  using Array = std::vector<Json>;
  using Object = std::vector<std::pair<std::string, Json>>;

  Json() = default;  // null
  Json(std::nullptr_t) {}
  Json(bool value) : value_(value) {}
  // Any integer type except bool and char types; throws std::out_of_range above INT64_MAX.
  template <std::integral T>
    requires(!std::same_as<T, bool> && !std::same_as<T, char> && !std::same_as<T, char8_t> &&
             !std::same_as<T, char16_t> && !std::same_as<T, char32_t> &&
             !std::same_as<T, wchar_t>)
  Json(T value) : value_(to_int64(value)) {}
  // Finite values are written in shortest round-trip form; NaN and +-inf are written as null.
  Json(double value) : value_(value) {}
  Json(float value) : value_(static_cast<double>(value)) {}
  // Strings are UTF-8 and written unchanged except for the escapes JSON requires.
  Json(std::string value) : value_(std::move(value)) {}
  Json(std::string_view value) : value_(std::string(value)) {}
  Json(const char* value) : value_(std::string(value)) {}

  static Json object();  // {}
  static Json array();   // []

  bool is_null() const { return std::holds_alternative<std::nullptr_t>(value_); }
  bool is_object() const { return std::holds_alternative<Object>(value_); }
  bool is_array() const { return std::holds_alternative<Array>(value_); }
  // Members of an object, elements of an array, 0 for scalars and null.
  std::size_t size() const;

  // The member `key` of an object, appended as null if absent. A null value becomes an empty
  // object first. Throws std::logic_error on any other kind of value. The reference is valid
  // until the next member is added to this object.
  Json& operator[](std::string_view key);
  // Appends `value` to an array and returns a reference to it (valid until the next append).
  // A null value becomes an empty array first. Throws std::logic_error on any other kind.
  Json& push_back(Json value);

  // The document, pretty-printed: two-space indentation, one member or element per line,
  // "key": value, empty containers as {} and [], and a trailing newline.
  std::string dump() const;

 private:
  template <std::integral T>
  static std::int64_t to_int64(T value) {
    if constexpr (std::is_unsigned_v<T> && sizeof(T) >= sizeof(std::int64_t)) {
      if (value > static_cast<T>(std::numeric_limits<std::int64_t>::max())) {
        throw std::out_of_range("Json: integer " + std::to_string(value) + " exceeds int64");
      }
    }
    return static_cast<std::int64_t>(value);
  }
  void dump_to(std::string& out, int indent) const;

  std::variant<std::nullptr_t, bool, std::int64_t, double, std::string, Array, Object> value_;
};

}  // namespace ricochet
