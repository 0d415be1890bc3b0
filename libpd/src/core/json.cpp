#include "libpd/core/json.hpp"

#include "libpd/core/text.hpp"

#include <cmath>
#include <fmt/format.h>

namespace pd {

Json& Json::operator[](const std::string& key) {
  if (std::holds_alternative<std::nullptr_t>(value_)) {
    value_ = Object{};
  }
  auto& obj = std::get<Object>(value_);
  for (auto& [k, v] : obj) {
    if (k == key) {
      return v;
    }
  }
  obj.emplace_back(key, Json{});
  return obj.back().second;
}

const Json* Json::find(const std::string& key) const {
  if (const Object* o = std::get_if<Object>(&value_)) {
    for (const auto& [k, v] : *o) {
      if (k == key) {
        return &v;
      }
    }
  }
  return nullptr;
}

std::optional<bool> Json::boolean() const {
  if (const bool* b = std::get_if<bool>(&value_)) {
    return *b;
  }
  return std::nullopt;
}

std::optional<std::string> Json::text() const {
  if (const std::string* t = std::get_if<std::string>(&value_)) {
    return *t;
  }
  return std::nullopt;
}

std::optional<double> Json::number() const {
  if (const double* d = std::get_if<double>(&value_)) {
    return *d;
  }
  if (const long long* i = std::get_if<long long>(&value_)) {
    return static_cast<double>(*i);
  }
  return std::nullopt;
}

void Json::push_back(Json v) {
  if (std::holds_alternative<std::nullptr_t>(value_)) {
    value_ = Array{};
  }
  std::get<Array>(value_).push_back(std::move(v));
}

namespace {
// Strings are made valid UTF-8 first (a scene title may hold any bytes): parsers reject the
// file otherwise.
std::string quote(const std::string& raw) {
  const std::string s = valid_utf8(raw);
  std::string out = "\"";
  for (char ch : s) {
    switch (ch) {
    case '"':
      out += "\\\"";
      break;
    case '\\':
      out += "\\\\";
      break;
    case '\n':
      out += "\\n";
      break;
    case '\t':
      out += "\\t";
      break;
    default:
      if (static_cast<unsigned char>(ch) < 0x20 || ch == 0x7F) {
        out += fmt::format("\\u{:04x}", static_cast<int>(ch));
      } else {
        out += ch;
      }
    }
  }
  return out + "\"";
}
} // namespace

void Json::dump_to(std::string& out, int indent, int depth) const {
  const std::string pad(static_cast<std::size_t>(indent * (depth + 1)), ' ');
  const std::string close_pad(static_cast<std::size_t>(indent * depth), ' ');
  const char* nl = indent > 0 ? "\n" : "";
  if (std::holds_alternative<std::nullptr_t>(value_)) {
    out += "null";
  } else if (const bool* b = std::get_if<bool>(&value_)) {
    out += *b ? "true" : "false";
  } else if (const double* d = std::get_if<double>(&value_)) {
    out += std::isfinite(*d) ? fmt::format("{}", *d) : "null";
  } else if (const long long* i = std::get_if<long long>(&value_)) {
    out += fmt::format("{}", *i);
  } else if (const std::string* s = std::get_if<std::string>(&value_)) {
    out += quote(*s);
  } else if (const Array* a = std::get_if<Array>(&value_)) {
    // Arrays of plain numbers stay on one line: deflection lines remain readable.
    bool flat = true;
    for (const Json& v : *a) {
      flat = flat && !v.is_object() && !std::holds_alternative<Array>(v.value_);
    }
    out += "[";
    for (std::size_t k = 0; k < a->size(); ++k) {
      if (!flat) {
        out += nl + pad;
      }
      (*a)[k].dump_to(out, indent, depth + 1);
      if (k + 1 < a->size()) {
        out += flat ? ", " : ",";
      }
    }
    if (!flat && !a->empty()) {
      out += nl + close_pad;
    }
    out += "]";
  } else if (const Object* o = std::get_if<Object>(&value_)) {
    out += "{";
    std::size_t k = 0;
    for (const auto& [key, member] : *o) {
      out += nl + pad + quote(key) + (indent > 0 ? ": " : ":");
      member.dump_to(out, indent, depth + 1);
      if (++k < o->size()) {
        out += ",";
      }
    }
    if (!o->empty()) {
      out += nl + close_pad;
    }
    out += "}";
  }
}

std::string Json::dump(int indent) const {
  std::string out;
  dump_to(out, indent, 0);
  return out + "\n";
}

} // namespace pd
