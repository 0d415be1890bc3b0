// Words for enum values: one table per enum, written beside the enum, gives each value its word
// (as scene files, command lines and summaries spell it) and a line of documentation.
//
// The scene parser, `to_string`, the command line's option checks and the scene template all read
// these tables, so a value cannot be spelt two ways or be offered in one place and not another.
// A table is declared by specialising `EnumName`:
//
//   template <> struct EnumName<StretchKind> {
//     static constexpr NameTable<StretchKind, 3> table{{{"exact", StretchKind::exact, ""}, ...}};
//   };
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace pd {

/// One row of a name table: the word, the value it stands for, and what it means.
template <class V>
struct NameEntry {
  std::string_view word;
  V value;
  std::string_view doc;
};

template <class V, std::size_t N>
using NameTable = std::array<NameEntry<V>, N>;

/// Specialised beside each enum with `static constexpr NameTable<E, N> table`.
template <class E>
struct EnumName;

template <class E>
concept NamedEnum = requires {
  EnumName<E>::table;
};

/// The word of a value ("?" if the table lacks it, which only a cast of a bad integer can do).
template <NamedEnum E>
constexpr std::string_view name_of(E value) {
  for (const auto& entry : EnumName<E>::table) {
    if (entry.value == value) {
      return entry.word;
    }
  }
  return "?";
}

/// The value a word stands for, if any.
template <NamedEnum E>
constexpr std::optional<E> from_name(std::string_view word) {
  for (const auto& entry : EnumName<E>::table) {
    if (entry.word == word) {
      return entry.value;
    }
  }
  return std::nullopt;
}

/// All words of a table, in table order (the order in which they are offered and documented).
template <class V, std::size_t N>
constexpr std::array<std::string_view, N> words_of(const NameTable<V, N>& table) {
  std::array<std::string_view, N> out{};
  for (std::size_t i = 0; i < N; ++i) {
    out[i] = table[i].word;
  }
  return out;
}

template <NamedEnum E>
inline constexpr auto enum_words = words_of(EnumName<E>::table);

/// All values of a table, in table order.
template <NamedEnum E>
constexpr auto enum_values() {
  std::array<E, EnumName<E>::table.size()> out{};
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i] = EnumName<E>::table[i].value;
  }
  return out;
}

/// The words as strings, for command-line option checks (CLI::IsMember).
template <NamedEnum E>
std::vector<std::string> enum_word_list() {
  return {enum_words<E>.begin(), enum_words<E>.end()};
}

} // namespace pd
