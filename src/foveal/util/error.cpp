// foveal/util/error.cpp — errors in the caller's words.
#include "foveal/util/error.h"

namespace foveal {

namespace {

bool word_char(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_'; }

}  // namespace

std::string in_words(std::string_view message, std::span<const ParameterName> names) {
  std::string out(message);
  // The parameter the message begins with ("NAME: …"; the longest name that fits)
  const ParameterName* lead = nullptr;
  for (const ParameterName& n : names)
    if (out.size() > n.library.size() && out.compare(0, n.library.size(), n.library) == 0 && out[n.library.size()] == ':' &&
        (!lead || n.library.size() > lead->library.size()))
      lead = &n;
  size_t from = 0;
  if (lead) {
    out.replace(0, lead->library.size(), lead->front_end);
    from = lead->front_end.size();
  }
  // Other parameters it mentions: snake_case names alone (a plain word such as "size" may be just a word)
  for (const ParameterName& n : names) {
    if (n.library.find('_') == std::string_view::npos) continue;
    for (size_t at = out.find(n.library, from); at != std::string::npos; at = out.find(n.library, at)) {
      const size_t end = at + n.library.size();
      if ((at > 0 && word_char(out[at - 1])) || (end < out.size() && word_char(out[end]))) {
        at = end;
        continue;
      }
      out.replace(at, n.library.size(), n.front_end);
      at += n.front_end.size();
    }
  }
  return out;
}

}  // namespace foveal
