// foveal/util/text.h — line and field splitting for every text reader (recordings, label files, visual
// fields, eye profiles, scenes), with exact numbers, and the one rule for a byte-order mark.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace foveal::text {

// Walks the lines of a text (LF or CRLF), counting from 1.
class Lines {
 public:
  explicit Lines(std::string_view text) : text_(text) {}
  // The next line without its end; false at the end of the text.
  bool next(std::string_view& line);
  int number() const { return number_; }

 private:
  std::string_view text_;
  size_t pos_ = 0;
  int number_ = 0;
};

// Fields separated by `separator` (kept empty between two separators); whitespace-separated when ' '.
std::vector<std::string_view> split(std::string_view line, char separator);
std::string_view trim(std::string_view s);

// A whole field as a finite number ("1.5", "-3", "1e-3"); nullopt for anything else.
// With decimal_comma, "1,5" reads as 1.5 (Tobii Pro Lab in some locales).
std::optional<double> to_number(std::string_view field, bool decimal_comma = false);

// A whole file; throws Error naming it when it cannot be opened, is a folder, or is larger than
// `max_bytes` (default 1 GiB, some 15 million samples of an EyeLink ASC file: an endless input such
// as /dev/zero is refused, not read until memory runs out).
inline constexpr size_t kMaxTextBytes = size_t(1) << 30;
std::string read_file(const std::string& path, size_t max_bytes = kMaxTextBytes);
// The same, or "" where it cannot be read (the kernel's files under /proc and /sys, which may be absent)
std::string read_file_or_empty(const std::string& path, size_t max_bytes = kMaxTextBytes);
// A UTF-8 byte-order mark at the start (spreadsheet programs on Windows write one): every text
// reader drops it.
inline bool has_bom(std::string_view text) { return text.substr(0, 3) == "\xEF\xBB\xBF"; }
// The text without its byte-order mark, if it has one.
inline std::string_view strip_bom(std::string_view text) { return has_bom(text) ? text.substr(3) : text; }

// A message for a terminal, as one line: bytes that are not valid UTF-8 (a binary file's, quoted
// in a decoder's complaint) and control characters become \xNN, as Python's "backslashreplace"
// shows them; valid UTF-8 (°, ×, names in any script) is kept.
std::string printable(std::string_view message);

}  // namespace foveal::text
