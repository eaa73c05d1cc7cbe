// foveal/io/image_io.h — reading and writing images: PNG/JPEG (8-bit), PFM and EXR (float).
#pragma once

#include "foveal/util/image.h"
#include "foveal/util/image_file.h"

#include <cstdint>
#include <string>
#include <vector>

namespace foveal {

// Linear value → sRGB-encoded value in [0, 1].
float linear_to_srgb(float v);
// The inverse of the sRGB curve (IEC 61966-2-1) on a value in [0, 1]: display-encoded to linear.
float srgb_to_linear(float v);
// Linear value → sRGB byte, lround(255·linear_to_srgb(v)) by table (what 8-bit files and the viewer show).
uint8_t srgb_byte(float v);
// A linear image's floats (`height` rows of `width` pixels of `channels`, interleaved) → sRGB-encoded
// floats into `out` (the same layout; `in` itself where rows are not reversed): each value clipped to
// [0, 1], encoded (within 1e-6 of linear_to_srgb, by a table of 65,537 values interpolated: no pow
// per value) and mapped to [low, high]; a 4th channel (alpha) is clipped and mapped, not encoded.
// `bottom_up` writes the rows in reverse order, as OpenGL's textures take them (PsychoPy's ImageStim:
// low −1, high 1). On foveal's threads; what a display shows every frame, so one pass, no pow. Throws
// Error naming the first value that is not finite (pixel x, y, channel), before writing anything.
void linear_to_srgb(const float* in, float* out, int width, int height, int channels, float low, float high, bool bottom_up);
// Linear RGB (or grey) → sRGB bytes with alpha 255, as save_image() writes a PNG.
Rgba8 to_rgba8(const Image& linear);
// Write 8-bit RGBA as PNG/JPEG/BMP (alpha dropped); throws Error naming the file.
void save_rgba8(const Rgba8& image, const std::string& path);

// The size caps on images read (kMaxImagePixels, kPerceiveBytesPerPixel): foveal/util/image_file.h

// Write by extension: .png (8-bit; `srgb` encodes linear colour, alpha is stored as is), .jpg/.bmp
// (8-bit, no alpha), .pfm or .exr (float, as is). 1, 3 or 4 (RGBA, PNG only) channels.
// Throws Error naming the file on failure.
void save_image(const Image& image, const std::string& path, bool srgb = true);
// The extensions save_image writes (lower case, with the dot): 8-bit .png, .jpg, .jpeg, .bmp,
// .ppm, and the float .pfm and .exr — what a command checks an image output against up front.
const std::vector<std::string>& image_extensions();
// Read by extension: .pfm, .exr (float, as stored), or any format OpenCV reads (values in [0,1],
// as stored: no sRGB decoding). RGBA files give 3 channels, or 4 with `keep_alpha` (alpha in
// [0,1]). Throws Error naming the file and the reason.
Image load_image(const std::string& path, bool keep_alpha = false);
// Integer pixels (8- or 16-bit, `bits`; interleaved, rows top to bottom) as values in [0, 1]
// exactly as load_image gives a file's (the same conversion, to the last bit): what the Python
// package does with a uint8/uint16 array.
Image image_from_integers(const void* pixels, int width, int height, int channels, int bits);

// Portable float map (1 or 3 channels); written by hand since it is a 3-line header and raw floats.
void save_pfm(const Image& image, const std::string& path);
Image load_pfm(const std::string& path);
// Parse PFM bytes (for tests and fuzzing); `name` appears in error messages.
Image parse_pfm(const std::string& bytes, const std::string& name);

// OpenEXR, 32-bit float channels Y or R,G,B.
void save_exr(const Image& image, const std::string& path);
Image load_exr(const std::string& path);

}  // namespace foveal
