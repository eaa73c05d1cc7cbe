// libFuzzer target: the visual-field reader must turn any bytes into fields or an Error, with and
// without a named grid (the first byte chooses none, 24-2, 30-2 or 10-2, and the default eye).
#include "foveal/impair/field.h"
#include "foveal/util/error.h"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  static const char* grids[] = {"", "24-2", "30-2", "10-2"};
  const std::string grid = grids[data[0] % 4];
  const foveal::Eye eye = (data[0] & 4) ? foveal::Eye::os : foveal::Eye::od;
  try {
    const auto fields = foveal::parse_field_csv(std::string(reinterpret_cast<const char*>(data + 1), size - 1), "fuzz.csv", grid, eye, 60);
    for (const auto& f : fields)
      for (double y : {-10.0, -0.5, 0.0, 0.5, 10.0}) (void)foveal::interpolate_loss_db(f, 3.0, y);
  } catch (const foveal::Error&) {}
  return 0;
}
