// libFuzzer target: perceive's image input path — any bytes under a PNG, JPEG, BMP or PFM name must
// give an image within the size cap (1–4 channels, as perceive takes them) or an Error, never a
// crash, a hang or an allocation beyond the cap. The first byte picks the extension; the rest is
// the file; OpenCV decodes by the content, so TIFF and PPM content (seeds here) reaches its
// decoders under any of these names, headers checked first. (EXR goes to OpenEXR by its name; it
// is left to that library's own fuzzing.)
#include "foveal/io/image_io.h"
#include "foveal/util/error.h"

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* const extensions[] = {".png", ".jpg", ".bmp", ".pfm"};
  const std::string path =
      (std::filesystem::temp_directory_path() / ("foveal-fuzz-image-" + std::to_string(getpid()) + extensions[data[0] % 4])).string();
  {
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
  }
  try {
    const foveal::Image im = foveal::load_image(path, true);
    if (im.width < 1 || im.height < 1 || uint64_t(im.width) * im.height > foveal::kMaxImagePixels) __builtin_trap();
    if (im.channels < 1 || im.channels > 4 || im.pixels.size() != size_t(im.width) * im.height * im.channels) __builtin_trap();
  } catch (const foveal::Error&) {}
  std::error_code ec;
  std::filesystem::remove(path, ec);
  return 0;
}
