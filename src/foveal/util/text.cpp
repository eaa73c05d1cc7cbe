// foveal/util/text.cpp — line and field splitting.
#include "foveal/util/text.h"

#include "foveal/util/error.h"
#include "foveal/util/files.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <array>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace foveal::text {

bool Lines::next(std::string_view& line) {
  if (pos_ >= text_.size()) return false;
  size_t end = text_.find('\n', pos_);
  if (end == std::string_view::npos) end = text_.size();
  line = text_.substr(pos_, end - pos_);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  pos_ = end + 1;
  ++number_;
  return true;
}

std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r");
  return s.substr(first, last - first + 1);
}

std::vector<std::string_view> split(std::string_view line, char separator) {
  std::vector<std::string_view> fields;
  if (separator == ' ') {
    size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
      if (i >= line.size()) break;
      const size_t start = i;
      while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
      fields.push_back(line.substr(start, i - start));
    }
    return fields;
  }
  size_t start = 0;
  for (;;) {
    const size_t end = line.find(separator, start);
    if (end == std::string_view::npos) {
      fields.push_back(line.substr(start));
      return fields;
    }
    fields.push_back(line.substr(start, end - start));
    start = end + 1;
  }
}

std::optional<double> to_number(std::string_view field, bool decimal_comma) {
  field = trim(field);
  if (field.empty()) return std::nullopt;
  std::string buffer;
  if (field.front() == '+') field.remove_prefix(1);
  if (decimal_comma && field.find(',') != std::string_view::npos && field.find('.') == std::string_view::npos) {
    buffer.assign(field);
    for (char& c : buffer)
      if (c == ',') c = '.';
    field = buffer;
  }
  double value = 0;
  const auto [end, error] = std::from_chars(field.data(), field.data() + field.size(), value);
  if (error != std::errc() || end != field.data() + field.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

std::string read_file(const std::string& path, size_t max_bytes) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) fail("{}: is a folder, not a file", path);
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("{}: cannot open file", path);
  note_input(path);
  // Bounded: an endless or huge input (/dev/zero, a disk image given by mistake) is refused once it
  // passes the limit instead of reading until memory runs out
  std::string out;
  std::array<char, 1 << 16> chunk;
  while (in) {
    in.read(chunk.data(), chunk.size());
    const size_t got = static_cast<size_t>(in.gcount());
    if (out.size() + got > max_bytes)
      fail("{}: more than {} MiB; foveal reads text inputs of up to {} MiB", path, max_bytes >> 20, max_bytes >> 20);
    out.append(chunk.data(), got);
  }
  if (in.bad()) fail("{}: read error", path);
  return out;
}

std::string read_file_or_empty(const std::string& path, size_t max_bytes) {
  try {
    return read_file(path, max_bytes);
  } catch (const Error&) {
    return {};
  }
}

std::string printable(std::string_view message) {
  std::string out;
  out.reserve(message.size());
  auto escape = [&](unsigned char b) { out += fmt::format("\\x{:02x}", b); };
  const auto* p = reinterpret_cast<const unsigned char*>(message.data());
  const size_t n = message.size();
  for (size_t i = 0; i < n;) {
    const unsigned char b = p[i];
    if (b < 0x80) {
      if (b < 0x20 || b == 0x7F)
        escape(b);
      else
        out += static_cast<char>(b);
      ++i;
      continue;
    }
    // The length of a well-formed sequence and its second byte's range (Unicode 15, table 3-7):
    // no overlong forms, no surrogates, nothing past U+10FFFF
    const size_t length = b >= 0xC2 && b <= 0xDF ? 2 : b >= 0xE0 && b <= 0xEF ? 3 : b >= 0xF0 && b <= 0xF4 ? 4 : 0;
    const unsigned char lo = b == 0xE0 ? 0xA0 : b == 0xF0 ? 0x90 : 0x80, hi = b == 0xED ? 0x9F : b == 0xF4 ? 0x8F : 0xBF;
    bool ok = length != 0 && i + length <= n && p[i + 1] >= lo && p[i + 1] <= hi;
    for (size_t k = 2; ok && k < length; ++k) ok = p[i + k] >= 0x80 && p[i + k] <= 0xBF;
    if (!ok) {
      escape(b);
      ++i;
      continue;
    }
    out.append(message.substr(i, length));
    i += length;
  }
  return out;
}

}  // namespace foveal::text
