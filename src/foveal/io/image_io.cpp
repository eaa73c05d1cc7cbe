// foveal/io/image_io.cpp — PNG through OpenCV, PFM by hand, EXR through OpenEXR.
#include "foveal/io/image_io.h"

#include "foveal/util/error.h"
#include "foveal/util/files.h"
#include "foveal/util/image_file.h"
#include "foveal/util/text.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fcntl.h>
#include <mutex>
#include <unistd.h>
#include <optional>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace foveal {
namespace {}  // namespace

float srgb_to_linear(float v) { return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f); }

float linear_to_srgb(float v) {
  if (!(v > 0)) return 0.0f;
  if (v >= 1) return 1.0f;
  return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

namespace {

// The 255 linear values where the sRGB byte steps up: byte(v) = number of steps ≤ v. Found by
// bisection on lround(255·linear_to_srgb(v)) itself, so a byte found among them is exactly that
// rounding, without a pow (the function is monotonic; tested over every step).
const std::array<float, 255>& srgb_steps() {
  static const std::array<float, 255> steps = [] {
    std::array<float, 255> t{};
    auto byte = [](float v) { return std::lround(linear_to_srgb(v) * 255.0f); };
    for (int k = 1; k <= 255; ++k) {
      float lo = 0.0f, hi = 1.0f;  // byte(lo) < k ≤ byte(hi)
      while (std::nextafter(lo, 2.0f) < hi) {
        const float mid = std::max(std::nextafter(lo, 2.0f), std::min(std::nextafter(hi, -1.0f), 0.5f * (lo + hi)));
        (byte(mid) >= k ? hi : lo) = mid;
      }
      t[k - 1] = hi;
    }
    return t;
  }();
  return steps;
}

constexpr std::array kEightBit = {".png", ".jpg", ".jpeg", ".bmp", ".ppm"};

// An 8-bit BGR(A) or grey matrix to PNG/JPEG/BMP/PPM.
void write_8bit(const cv::Mat& mat, const std::string& path) {
  const std::string ext = lower_extension(path);
  if (std::find(kEightBit.begin(), kEightBit.end(), ext) == kEightBit.end())
    fail("{}: unknown image format '{}' (use .png, .jpg, .pfm or .exr)", path, ext);
  bool ok = false;
  try {
    ok = cv::imwrite(path, mat);
  } catch (const cv::Exception& e) {
    fail("{}: cannot write image: {}", path, e.what());
  }
  if (!ok) fail("{}: cannot write image (does the folder exist?)", path);
}

// Where to start looking: the byte at the lower edge of each of 4096 equal buckets of [0, 1]
// (the sRGB curve is steepest at 0, 3.2 bytes per 1/4096, so a few steps from there at most).
const std::array<uint8_t, 4097>& srgb_bucket_start() {
  static const std::array<uint8_t, 4097> start = [] {
    const auto& steps = srgb_steps();
    std::array<uint8_t, 4097> t{};
    for (int b = 0; b <= 4096; ++b) t[b] = static_cast<uint8_t>(std::upper_bound(steps.begin(), steps.end(), b / 4096.0f) - steps.begin());
    return t;
  }();
  return start;
}

inline uint8_t srgb_byte(float v, const float* steps, const uint8_t* start) {
  if (!(v > 0)) return 0;  // also NaN
  if (v >= 1) return 255;
  // One bucket early, in case v·4096 rounded up to the next bucket's edge
  const int b = static_cast<int>(v * 4096.0f);
  int i = start[b > 0 ? b - 1 : 0];
  while (i < 255 && steps[i] <= v) ++i;
  return static_cast<uint8_t>(i);
}

}  // namespace

uint8_t srgb_byte(float v) { return srgb_byte(v, srgb_steps().data(), srgb_bucket_start().data()); }

namespace {

// linear_to_srgb at k / kSrgbTableSteps, k = 0 … kSrgbTableSteps: interpolated between neighbours it
// is within 1e-7 of the curve (the error of linear interpolation, h²/8 · |f''|, peaks at the curve's
// knee, 0.0031308: 7e-8), where a pow a value costs ~20 ns — 13 ms a frame at 840x525 on two cores
constexpr int kSrgbTableSteps = 65536;
const std::vector<float>& srgb_table() {
  static const std::vector<float> table = [] {
    std::vector<float> t(kSrgbTableSteps + 1);
    for (int k = 0; k <= kSrgbTableSteps; ++k)
      t[static_cast<size_t>(k)] = linear_to_srgb(static_cast<float>(static_cast<double>(k) / kSrgbTableSteps));
    return t;
  }();
  return table;
}

}  // namespace

void linear_to_srgb(const float* in, float* out, int width, int height, int channels, float low, float high, bool bottom_up) {
  const size_t row = static_cast<size_t>(width) * static_cast<size_t>(channels);
  if (bottom_up && in == out && height > 1) fail("image: rows reversed into the image itself would overwrite rows not yet read");
  // Every value finite, checked before anything is written (`out` may be `in`)
  std::atomic<size_t> first_bad{SIZE_MAX};
  tbb::parallel_for(0, height, [&](int y) {
    const float* p = in + static_cast<size_t>(y) * row;
    for (size_t i = 0; i < row; ++i)
      if (!std::isfinite(p[i])) {
        const size_t at = static_cast<size_t>(y) * row + i;
        size_t seen = first_bad.load();
        while (at < seen && !first_bad.compare_exchange_weak(seen, at)) {}
        return;
      }
  });
  if (const size_t at = first_bad.load(); at != SIZE_MAX) {
    const size_t pixel = at / static_cast<size_t>(channels);
    fail("image: pixel ({}, {}) channel {} is {}: a linear image's values are finite", pixel % static_cast<size_t>(width),
         pixel / static_cast<size_t>(width), at % static_cast<size_t>(channels), in[at]);
  }
  const float* table = srgb_table().data();
  const float span = high - low;
  tbb::parallel_for(0, height, [&](int y) {
    const float* p = in + static_cast<size_t>(y) * row;
    float* q = out + static_cast<size_t>(bottom_up ? height - 1 - y : y) * row;
    for (size_t i = 0; i < row; ++i) {
      const float v = std::clamp(p[i], 0.0f, 1.0f);
      float e = v;
      if (channels != 4 || i % 4 != 3) {  // (alpha is no colour)
        const float x = v * static_cast<float>(kSrgbTableSteps);
        const int k = std::min(static_cast<int>(x), kSrgbTableSteps - 1);
        const float f = x - static_cast<float>(k);
        e = table[k] + f * (table[k + 1] - table[k]);
      }
      q[i] = low + span * e;
    }
  });
}

Rgba8 to_rgba8(const Image& linear) {
  Rgba8 out(linear.width, linear.height);
  const int c = linear.channels;
  const float* steps = srgb_steps().data();
  const uint8_t* start = srgb_bucket_start().data();
  tbb::parallel_for(0, linear.height, [&](int y) {
    for (int x = 0; x < linear.width; ++x) {
      uint8_t* p = out.at(x, y);
      for (int k = 0; k < 3; ++k) p[k] = srgb_byte(linear.at(x, y, c >= 3 ? k : 0), steps, start);
    }
  });
  return out;
}

void save_rgba8(const Rgba8& image, const std::string& path) {
  if (image.empty()) fail("{}: cannot write an empty image", path);
  const cv::Mat rgba(image.height, image.width, CV_8UC4, const_cast<uint8_t*>(image.px.data()));
  cv::Mat bgr;
  cv::cvtColor(rgba, bgr, cv::COLOR_RGBA2BGR);
  write_8bit(bgr, path);
}

const std::vector<std::string>& image_extensions() {
  static const std::vector<std::string> all = [] {
    std::vector<std::string> e(kEightBit.begin(), kEightBit.end());
    e.insert(e.end(), {".pfm", ".exr"});
    return e;
  }();
  return all;
}

void save_image(const Image& image, const std::string& path, bool srgb) {
  check_not_an_input(path);
  if (image.empty()) fail("{}: cannot write an empty image", path);
  const std::string ext = lower_extension(path);
  if (ext == ".pfm") return save_pfm(image, path);
  if (ext == ".exr") return save_exr(image, path);
  // 8-bit, BGR(A) order for OpenCV; alpha is stored linearly (it is a coverage, not a colour)
  if (image.channels != 1 && image.channels != 3 && image.channels != 4)
    fail("{}: {} channels; 8-bit images hold 1 (grey), 3 (RGB) or 4 (RGBA)", path, image.channels);
  if (image.channels == 4 && ext != ".png") fail("{}: '{}' keeps no alpha channel; write the RGBA image as .png", path, ext);
  const int type = image.channels == 1 ? CV_8UC1 : image.channels == 3 ? CV_8UC3 : CV_8UC4;
  auto linear_byte = [](float v) {
    return static_cast<uint8_t>(std::lround(std::clamp(std::isfinite(v) ? v : 0.0f, 0.0f, 1.0f) * 255.0f));
  };
  cv::Mat mat(image.height, image.width, type);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      for (int c = 0; c < image.channels; ++c) {
        const float v = image.at(x, y, c);
        const int channel = image.channels == 1 || c == 3 ? c : 2 - c;
        mat.ptr<uint8_t>(y)[x * mat.channels() + channel] = srgb && c < 3 ? srgb_byte(v) : linear_byte(v);
      }
  write_8bit(mat, path);
}

Image image_from_integers(const void* pixels, int width, int height, int channels, int bits) {
  if (bits != 8 && bits != 16) fail("image: {}-bit pixels; 8 or 16 bits are read", bits);
  if (channels < 1 || channels > 4 || width <= 0 || height <= 0) fail("image: {}x{} with {} channels", width, height, channels);
  const cv::Mat mat(height, width, CV_MAKETYPE(bits == 8 ? CV_8U : CV_16U, channels), const_cast<void*>(pixels));
  Image img(width, height, channels);
  cv::Mat out(height, width, CV_MAKETYPE(CV_32F, channels), img.pixels.data());
  mat.convertTo(out, CV_MAKETYPE(CV_32F, channels), bits == 16 ? 1.0 / 65535.0 : 1.0 / 255.0);  // load_image's scale
  return img;
}

Image load_image(const std::string& path, bool keep_alpha) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) fail("{}: no such file", path);
  if (std::filesystem::is_directory(path, ec)) fail("{}: is a folder, not an image", path);
  note_input(path);
  const std::string ext = lower_extension(path);
  if (ext == ".pfm") return load_pfm(path);
  if (ext == ".exr") return load_exr(path);
  check_image_file(path);
  cv::Mat mat;
  try {
    // The decoders' own complaints ("libpng error: Read Error") would come before foveal's line
    // naming the file: stderr is closed to them while they decode (one decode at a time). Not in
    // fuzzing builds, where a crash or allocation report from inside a decoder must be seen.
    static std::mutex decoding;
    const std::lock_guard lock(decoding);
#ifdef FOVEAL_FUZZING
    const int saved = -1, null = -1;
#else
    const int saved = ::dup(STDERR_FILENO), null = ::open("/dev/null", O_WRONLY);
#endif
    if (saved >= 0 && null >= 0) ::dup2(null, STDERR_FILENO);
    struct Restore {
      int saved, null;
      ~Restore() {
        if (saved >= 0) ::dup2(saved, STDERR_FILENO), ::close(saved);
        if (null >= 0) ::close(null);
      }
    } restore{saved, null};
    mat = cv::imread(path, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {  // OpenCV's own assertions: with the file's name, on one line
    fail("{}: cannot read image: {}", path, e.err);
  }
  if (mat.empty()) fail("{}: cannot read image (unknown or corrupt format)", path);
  if (mat.channels() == 4 && !keep_alpha) cv::cvtColor(mat, mat, cv::COLOR_BGRA2BGR);
  if (mat.channels() == 2) cv::cvtColor(mat, mat, cv::COLOR_BGRA2BGR);  // grey + alpha: not a layout foveal keeps
  const double scale = mat.depth() == CV_16U ? 1.0 / 65535.0 : mat.depth() == CV_8U ? 1.0 / 255.0 : 1.0;
  mat.convertTo(mat, CV_MAKETYPE(CV_32F, mat.channels()), scale);
  Image image(mat.cols, mat.rows, mat.channels() == 1 ? 1 : mat.channels() == 4 ? 4 : 3);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      for (int c = 0; c < image.channels; ++c)
        image.at(x, y, c) = mat.ptr<float>(y)[x * mat.channels() + (image.channels == 1 || c == 3 ? c : 2 - c)];
  return image;
}

void save_pfm(const Image& image, const std::string& path) {
  if (image.channels != 1 && image.channels != 3) fail("{}: PFM holds 1 or 3 channels, not {}", path, image.channels);
  std::ofstream out(path, std::ios::binary);
  if (!out) fail("{}: cannot open for writing", path);
  // Header; a negative scale means little-endian. Rows are stored bottom to top.
  out << (image.channels == 3 ? "PF" : "Pf") << "\n"
      << image.width << " " << image.height << "\n"
      << (std::endian::native == std::endian::little ? "-1.0" : "1.0") << "\n";
  for (int y = image.height - 1; y >= 0; --y)
    out.write(reinterpret_cast<const char*>(&image.pixels[static_cast<size_t>(y) * image.width * image.channels]),
              static_cast<std::streamsize>(sizeof(float) * image.width * image.channels));
  if (!out) fail("{}: write failed", path);
}

Image parse_pfm(const std::string& bytes, const std::string& name) {
  std::istringstream in(bytes);
  std::string magic;
  long long w = 0, h = 0;
  double scale = 0;
  if (!(in >> magic) || (magic != "PF" && magic != "Pf")) fail("{}: not a PFM file (expected 'PF' or 'Pf')", name);
  if (!(in >> w >> h) || w <= 0 || h <= 0 || w > 65536 || h > 65536)
    fail("{}: bad PFM size (width and height must be in [1, 65536])", name);
  if (!(in >> scale) || scale == 0 || !std::isfinite(scale)) fail("{}: bad PFM scale (must be a non-zero number)", name);
  // The single whitespace byte before the data; then the data must fit in what is left
  if (in.get() == std::char_traits<char>::eof() || in.tellg() < 0) fail("{}: truncated PFM header (no pixel data)", name);
  const auto offset = static_cast<size_t>(in.tellg());
  const int channels = magic == "PF" ? 3 : 1;
  const size_t row = static_cast<size_t>(w) * channels;
  const size_t need = sizeof(float) * row * static_cast<size_t>(h);
  if (offset > bytes.size() || bytes.size() - offset < need)
    fail("{}: truncated PFM data ({} bytes, need {})", name, bytes.size() - std::min(offset, bytes.size()), need);
  Image image(static_cast<int>(w), static_cast<int>(h), channels);
  const bool swap = (scale < 0) != (std::endian::native == std::endian::little);
  for (long long y = 0; y < h; ++y) {
    float* dst = &image.pixels[static_cast<size_t>(h - 1 - y) * row];
    std::memcpy(dst, bytes.data() + offset + sizeof(float) * row * y, sizeof(float) * row);
    if (swap)
      for (size_t k = 0; k < row; ++k) {
        uint32_t u;
        std::memcpy(&u, &dst[k], 4);
        u = __builtin_bswap32(u);
        std::memcpy(&dst[k], &u, 4);
      }
  }
  return image;
}

Image load_pfm(const std::string& path) { return parse_pfm(text::read_file(path), path); }

void save_exr(const Image& image, const std::string& path) {
  if (image.channels != 1 && image.channels != 3) fail("{}: EXR writer takes 1 or 3 channels, not {}", path, image.channels);
  try {
    Imf::Header header(image.width, image.height);
    const char* names[3] = {"R", "G", "B"};
    const int n = image.channels;
    for (int c = 0; c < n; ++c) header.channels().insert(n == 1 ? "Y" : names[c], Imf::Channel(Imf::FLOAT));
    Imf::OutputFile file(path.c_str(), header);
    Imf::FrameBuffer fb;
    const size_t xs = sizeof(float) * n, ys = xs * image.width;
    for (int c = 0; c < n; ++c)
      fb.insert(n == 1 ? "Y" : names[c], Imf::Slice(Imf::FLOAT, (char*)(image.pixels.data() + c), xs, ys));  // NOLINT: OpenEXR takes char*
    file.setFrameBuffer(fb);
    file.writePixels(image.height);
  } catch (const std::exception& e) {
    fail("{}: cannot write EXR: {}", path, e.what());
  }
}

Image load_exr(const std::string& path) {
  try {
    Imf::InputFile file(path.c_str());
    const Imath::Box2i dw = file.header().dataWindow();
    const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
    if (w < 1 || h < 1) fail("{}: an EXR data window of {}x{}", path, w, h);
    check_image_size(path, uint64_t(w), uint64_t(h));
    const bool gray = file.header().channels().findChannel("Y") != nullptr && file.header().channels().findChannel("R") == nullptr;
    const int n = gray ? 1 : 3;
    Image image(w, h, n);
    Imf::FrameBuffer fb;
    const char* names[3] = {"R", "G", "B"};
    const size_t xs = sizeof(float) * n, ys = xs * w;
    char* base = reinterpret_cast<char*>(image.pixels.data()) - (dw.min.x * xs + dw.min.y * ys);
    for (int c = 0; c < n; ++c) fb.insert(gray ? "Y" : names[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xs, ys, 1, 1, 0.0));
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    return image;
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    fail("{}: cannot read EXR: {}", path, e.what());
  }
}

}  // namespace foveal
