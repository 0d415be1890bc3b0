// A small JSON value for summaries and case records. Non-finite numbers are written as null.
#pragma once

#include <cstddef>
#include <limits>
#include <list>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace pd {

/// A small JSON value for summaries; keys keep their insertion order.
class Json {
public:
  using Array = std::vector<Json>;
  /// A list, so references to members stay valid while more members are added.
  using Object = std::list<std::pair<std::string, Json>>;

  Json() = default;
  Json(std::nullptr_t) {}
  Json(bool b) : value_(b) {}
  Json(double d) : value_(d) {}
  Json(int i) : value_(static_cast<long long>(i)) {}
  Json(long i) : value_(static_cast<long long>(i)) {}
  Json(long long i) : value_(i) {}
  Json(unsigned i) : value_(static_cast<long long>(i)) {}
  Json(unsigned long i) : Json(static_cast<unsigned long long>(i)) {}
  /// Values beyond the signed range are kept as (rounded) doubles rather than wrapping.
  Json(unsigned long long i) {
    if (i <= static_cast<unsigned long long>(std::numeric_limits<long long>::max())) {
      value_ = static_cast<long long>(i);
    } else {
      value_ = static_cast<double>(i);
    }
  }
  Json(std::string s) : value_(std::move(s)) {}
  Json(const char* s) : value_(std::string(s)) {}
  Json(Array a) : value_(std::move(a)) {}
  Json(Object o) : value_(std::move(o)) {}

  static Json object() { return Json(Object{}); }
  static Json array() { return Json(Array{}); }
  template <class T>
  static Json array_of(const std::vector<T>& values) {
    Array a;
    for (const T& v : values) {
      a.emplace_back(v);
    }
    return Json(std::move(a));
  }

  /// Object member, created (as null) if missing. Turns a null value into an object.
  Json& operator[](const std::string& key);
  void push_back(Json v);
  bool is_object() const { return std::holds_alternative<Object>(value_); }
  /// Member `key` of an object, or nullptr.
  const Json* find(const std::string& key) const;
  /// The value as bool / number, or nullopt for other types.
  std::optional<bool> boolean() const;
  std::optional<double> number() const;
  std::optional<std::string> text() const;
  /// The elements of an array; nullptr for any other value.
  const Array* items() const { return std::get_if<Array>(&value_); }

  /// Pretty-printed text. Non-finite numbers become null.
  std::string dump(int indent = 2) const;

private:
  void dump_to(std::string& out, int indent, int depth) const;
  std::variant<std::nullptr_t, bool, double, long long, std::string, Array, Object> value_{nullptr};
};

} // namespace pd
