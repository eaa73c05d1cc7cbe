// foveal/util/image_file.h — what an image file's first bytes say, before any decoder sees it: its
// format (only those foveal reads through OpenCV) and its size against foveal's caps. Used by
// load_image and by the scene's texture loader, so hostile content meets the same checks.
#pragma once

#include <cstdint>
#include <string>

namespace foveal {

// The largest image foveal reads, in pixels (8192 × 8192, an 8K frame fits): perceive holds up to
// kPerceiveBytesPerPixel bytes per pixel (with the eye's optics; 32 without: BENCHMARKS.md), so a
// frame at the cap peaks near 5.6 GB. Larger images (PNG, JPEG, BMP, PPM, TIFF, EXR, PFM) are
// refused from their header, before anything is decoded, as are those whose samples would decode
// to more than kMaxDecodedBytes (a 64-bit float TIFF); load_image reads no other format.
inline constexpr uint64_t kMaxImagePixels = uint64_t(8192) * 8192;
inline constexpr int kPerceiveBytesPerPixel = 84;
// What the largest float RGBA image takes (1 GiB)
inline constexpr uint64_t kMaxDecodedBytes = kMaxImagePixels * 4 * sizeof(float);

// Throws Error naming the file where width × height passes kMaxImagePixels.
void check_image_size(const std::string& path, uint64_t width, uint64_t height);
// Throws Error naming the file unless it starts with the whole signature of a PNG, JPEG, BMP, TIFF
// or PPM/PGM (P2, P3, P5, P6) and its header, where it states a size, is within the caps above.
void check_image_file(const std::string& path);

}  // namespace foveal
