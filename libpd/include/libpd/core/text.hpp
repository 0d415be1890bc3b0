// User text echoed back (in messages, on the terminal, in JSON): it may be huge, hold control
// bytes or not be UTF-8 at all. These are the one place that decides how such text is shown.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace pd {

/// Length in bytes of the valid UTF-8 sequence starting at s[i] (1–4), or 0 if the bytes there
/// are not one (overlong forms, surrogates and code points above U+10FFFF included).
std::size_t utf8_sequence_length(std::string_view s, std::size_t i);

/// `s` with every byte that is not part of valid UTF-8 replaced by U+FFFD, so that any JSON
/// parser accepts it.
std::string valid_utf8(std::string_view s);

/// `s` made safe to print: control bytes and invalid UTF-8 as \xNN, and text beyond
/// `max_bytes` cut, ending in "… (N bytes)" with the full size.
std::string printable(std::string_view s, std::size_t max_bytes = 80);

/// `message` with each word (between spaces and newlines) made printable and cut to
/// `max_word_bytes`: for messages that quote what the user wrote.
std::string printable_words(std::string_view message, std::size_t max_word_bytes = 60);

} // namespace pd
