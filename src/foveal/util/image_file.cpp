// foveal/util/image_file.cpp — image signatures and header sizes, read by hand before decoding.
#include "foveal/util/image_file.h"

#include "foveal/util/error.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cstring>
#include <fstream>
#include <optional>

namespace foveal {
namespace {

// What a PNG, JPEG, BMP, PPM or TIFF header states, read from its first bytes before anything is
// decoded: the pixels and the bytes OpenCV allocates for them (up to 4 channels). By hand because
// OpenCV 4.6 offers no header-only read (its own limit, 2^30 pixels, is read from the environment
// when the library loads, and a decode near it needs ~40 GB here; it allocates the whole frame
// before it finds a file truncated).
struct HeaderSize {
  uint64_t width = 0, height = 0;
  uint64_t bytes_per_pixel = 4;  // as decoded: channels × bytes per sample
};

// PPM/PGM (P2, P3, P5, P6): width, height and maximum value as decimal numbers, between which
// whitespace and '#' comments may fall (Netpbm's format pages).
std::optional<HeaderSize> netpbm_header(std::istream& in, char kind) {
  auto number = [&]() -> std::optional<uint64_t> {
    int c = in.get();
    while (c != EOF && (std::isspace(c) || c == '#')) {
      if (c == '#')
        while (c != EOF && c != '\n' && c != '\r') c = in.get();
      c = in.get();
    }
    if (c == EOF || !std::isdigit(c)) return std::nullopt;
    uint64_t v = 0;
    for (; c != EOF && std::isdigit(c); c = in.get()) v = std::min<uint64_t>(v * 10 + uint64_t(c - '0'), uint64_t(1) << 31);
    return v;
  };
  in.clear();
  in.seekg(2);
  const auto width = number(), height = number(), maximum = number();
  if (!width || !height || !maximum) return std::nullopt;
  const uint64_t channels = kind == '3' || kind == '6' ? 3 : 1;
  return HeaderSize{*width, *height, channels * (*maximum > 255 ? 2 : 1)};
}

// TIFF (classic, not BigTIFF): the first image file directory's ImageWidth (256), ImageLength (257),
// BitsPerSample (258) and SamplesPerPixel (277) entries (TIFF 6.0, section 2).
std::optional<HeaderSize> tiff_header(std::istream& in, bool little) {
  auto read = [&](uint64_t at, int n) -> std::optional<uint64_t> {
    unsigned char b[4]{};
    in.clear();
    in.seekg(static_cast<std::streamoff>(at));
    if (!in.read(reinterpret_cast<char*>(b), n)) return std::nullopt;
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v |= uint64_t(b[little ? i : n - 1 - i]) << (8 * i);
    return v;
  };
  const auto ifd = read(4, 4);
  const auto entries = ifd ? read(*ifd, 2) : std::nullopt;
  if (!entries) return std::nullopt;
  std::optional<uint64_t> width, height;
  uint64_t bits = 1, samples = 1;
  for (uint64_t i = 0; i < *entries; ++i) {
    const uint64_t at = *ifd + 2 + 12 * i;
    const auto tag = read(at, 2), type = read(at + 2, 2), count = read(at + 4, 4);
    if (!tag || !type || !count) return std::nullopt;
    const int size = *type == 3 ? 2 : *type == 4 ? 4 : 0;  // SHORT or LONG; others are not sizes
    if (size == 0 || *count == 0) continue;
    // A value that fits in four bytes is stored in the entry; otherwise the entry holds its offset
    std::optional<uint64_t> first = *count * size <= 4 ? read(at + 8, size) : std::nullopt;
    if (*count * size > 4)
      if (const auto offset = read(at + 8, 4)) first = read(*offset, size);
    if (!first) return std::nullopt;
    if (*tag == 256) width = first;
    if (*tag == 257) height = first;
    if (*tag == 258) bits = std::max<uint64_t>(*first, 1);
    if (*tag == 277) samples = std::max<uint64_t>(*first, 1);
  }
  if (!width || !height) return std::nullopt;
  return HeaderSize{*width, *height, std::min<uint64_t>(samples, 4) * ((std::min<uint64_t>(bits, 64) + 7) / 8)};
}

std::optional<HeaderSize> header_size(std::istream& in) {
  in.clear();
  in.seekg(0);
  std::array<unsigned char, 32> h{};
  in.read(reinterpret_cast<char*>(h.data()), h.size());
  const auto got = static_cast<size_t>(in.gcount());
  auto be32 = [&](size_t i) { return uint64_t(h[i]) << 24 | uint64_t(h[i + 1]) << 16 | uint64_t(h[i + 2]) << 8 | h[i + 3]; };
  auto le32 = [&](size_t i) { return uint64_t(h[i]) | uint64_t(h[i + 1]) << 8 | uint64_t(h[i + 2]) << 16 | uint64_t(h[i + 3]) << 24; };
  if (got >= 24 && h[0] == 0x89 && h[1] == 'P' && h[2] == 'N' && h[3] == 'G') return HeaderSize{be32(16), be32(20), 8};  // IHDR
  if (got >= 26 && h[0] == 'B' && h[1] == 'M') {
    const auto height = static_cast<int32_t>(le32(22));  // negative: rows stored top-down
    return HeaderSize{le32(18), uint64_t(height < 0 ? -int64_t(height) : height), 4};
  }
  if (got >= 2 && h[0] == 'P' && h[1] >= '2' && h[1] <= '6' && h[1] != '4') return netpbm_header(in, static_cast<char>(h[1]));
  if (got >= 8 && ((h[0] == 'I' && h[1] == 'I') || (h[0] == 'M' && h[1] == 'M'))) return tiff_header(in, h[0] == 'I');
  if (got >= 4 && h[0] == 0xFF && h[1] == 0xD8) {  // JPEG: the segments up to the first start-of-frame
    in.clear();
    in.seekg(2);
    for (int segments = 0; segments < 4096 && in; ++segments) {
      unsigned char m[4];
      if (!in.read(reinterpret_cast<char*>(m), 4) || m[0] != 0xFF) return std::nullopt;
      const unsigned length = unsigned(m[2]) << 8 | m[3];
      const bool sof = m[1] >= 0xC0 && m[1] <= 0xCF && m[1] != 0xC4 && m[1] != 0xC8 && m[1] != 0xCC;
      if (sof) {
        unsigned char f[5];
        if (!in.read(reinterpret_cast<char*>(f), 5)) return std::nullopt;
        return HeaderSize{uint64_t(f[3]) << 8 | f[4], uint64_t(f[1]) << 8 | f[2], 3};
      }
      if (length < 2) return std::nullopt;
      in.seekg(length - 2, std::ios::cur);
    }
  }
  return std::nullopt;
}

}  // namespace

void check_image_size(const std::string& path, uint64_t width, uint64_t height) {
  if (width * height > kMaxImagePixels)
    fail("{}: {}x{} pixels, more than the {} million foveal reads (perceive holds up to {} bytes per pixel); scale it down first", path,
         width, height, kMaxImagePixels / 1000000, kPerceiveBytesPerPixel);
}

void check_image_file(const std::string& path) {
  // Only the formats foveal reads through OpenCV: it picks its decoder by the content, the first
  // whose signature matches, and other content (DICOM under a .jpg name, found by fuzzing) reaches
  // decoders that abort the process. So the whole signature each of these decoders checks is
  // required here: "P6" followed by anything but whitespace is no PPM to OpenCV, and went on to
  // the DICOM decoder (also found by fuzzing).
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("{}: cannot be opened", path);
  std::array<unsigned char, 8> m{};
  in.read(reinterpret_cast<char*>(m.data()), m.size());
  const auto got = static_cast<size_t>(in.gcount());
  const bool png = got >= 8 && std::memcmp(m.data(), "\x89PNG\r\n\x1a\n", 8) == 0;
  const bool jpeg = got >= 3 && m[0] == 0xFF && m[1] == 0xD8 && m[2] == 0xFF;
  const bool bmp = got >= 3 && m[0] == 'B' && m[1] == 'M';
  const bool tiff =
      got >= 4 && ((m[0] == 'I' && m[1] == 'I' && m[2] == 42 && m[3] == 0) || (m[0] == 'M' && m[1] == 'M' && m[2] == 0 && m[3] == 42));
  const bool ppm =
      got >= 3 && m[0] == 'P' && m[1] >= '2' && m[1] <= '6' && m[1] != '4' && std::isspace(m[2]);  // (what save_image writes as .ppm)
  if (!(png || jpeg || bmp || tiff || ppm))
    fail("{}: not a PNG, JPEG, BMP, TIFF, PPM, EXR or PFM image (its first bytes are none of theirs)", path);
  const auto size = header_size(in);
  if (!size) return;
  check_image_size(path, size->width, size->height);
  if (size->width * size->height * size->bytes_per_pixel > kMaxDecodedBytes)
    fail("{}: {}x{} pixels of {} bytes each decode to more than {} MiB; convert it to 8 or 16 bits a sample first", path, size->width,
         size->height, size->bytes_per_pixel, kMaxDecodedBytes >> 20);
}

}  // namespace foveal
