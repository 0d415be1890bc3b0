// Binding a scene key to the field it fills: `field<&Struct::member, ...>()` in a key's `.bind`
// stores the key's value in that (possibly nested) member, read with the reader that the field's
// type calls for; `field_with_default` also makes the template write the member's default, taken
// from a default-constructed struct, so that the default is stated only in the struct.
#pragma once

#include "libpd/core/names.hpp"
#include "reader.hpp"

#include <concepts>
#include <type_traits>

namespace pd::scene {

template <class M>
struct MemberOf;
template <class C, class F>
struct MemberOf<F C::*> {
  using Struct = C;
};

/// object.*first.*...rest
template <auto First, auto... Rest>
constexpr auto& member_at(auto& object) {
  if constexpr (sizeof...(Rest) == 0) {
    return object.*First;
  } else {
    return member_at<Rest...>(object.*First);
  }
}

using Matrix3 = std::array<std::array<double, 3>, 3>;

template <class T>
void store_value(const Reader& r, const Fields& f, std::string_view key, T& field) {
  if constexpr (std::same_as<T, std::optional<double>>) {
    field = key_of(*f.schema, key).type == Type::number_or_auto ? r.number_or_auto(f, key)
                                                                : r.number(f, key);
  } else if constexpr (std::same_as<T, double>) {
    if (auto v = r.number(f, key)) {
      field = *v;
    }
  } else if constexpr (std::same_as<T, bool>) {
    if (auto v = r.boolean(f, key)) {
      field = *v;
    }
  } else if constexpr (std::integral<T>) {
    if (auto v = r.integer<T>(f, key)) {
      field = *v;
    }
  } else if constexpr (std::same_as<T, std::string>) {
    if (auto v = r.string(f, key)) {
      field = *v;
    }
  } else if constexpr (std::same_as<T, Vec3>) {
    if (auto v = r.vector(f, key)) {
      field = *v;
    }
  } else if constexpr (std::same_as<T, Matrix3>) {
    if (auto v = r.matrix(f, key)) {
      field = *v;
    }
  } else if constexpr (std::same_as<T, std::array<bool, 3>>) {
    if (auto v = r.components(f, key)) {
      field = *v;
    }
  } else {
    static_assert(NamedEnum<T>, "no scene reader for this field type");
    // The key declares `.choices = enum_words<T>`, so the index of its word is the table row.
    if (auto i = r.choice(f, key)) {
      field = EnumName<T>::table[static_cast<std::size_t>(*i)].value;
    }
  }
}

template <class T>
std::string yaml_text(const T& value) {
  if constexpr (std::same_as<T, double>) {
    return yaml_number(value);
  } else if constexpr (std::same_as<T, bool>) {
    return value ? "true" : "false";
  } else if constexpr (std::integral<T>) {
    return fmt::format("{}", value);
  } else if constexpr (std::same_as<T, Vec3>) {
    return fmt::format("[{}, {}, {}]", yaml_number(value[0]), yaml_number(value[1]),
                       yaml_number(value[2]));
  } else if constexpr (std::same_as<T, Matrix3>) {
    return fmt::format("[{}, {}, {}]", yaml_text(value[0]), yaml_text(value[1]),
                       yaml_text(value[2]));
  } else {
    static_assert(NamedEnum<T>, "no YAML text for this field type");
    return std::string(name_of(value));
  }
}

/// Store the key in `Struct{}.*Path...` (the first member pointer names the struct).
template <auto First, auto... Rest>
constexpr Binder field() {
  using S = typename MemberOf<decltype(First)>::Struct;
  return {&typeid(S),
          [](const Reader& r, const Fields& f, std::string_view key, void* target) {
            store_value(r, f, key, member_at<First, Rest...>(*static_cast<S*>(target)));
          },
          nullptr};
}

/// The same, and the template writes the member's default.
template <auto First, auto... Rest>
constexpr Binder field_with_default() {
  using S = typename MemberOf<decltype(First)>::Struct;
  Binder b = field<First, Rest...>();
  b.default_text = [] {
    S defaults{};
    return yaml_text(member_at<First, Rest...>(defaults));
  };
  return b;
}

} // namespace pd::scene
