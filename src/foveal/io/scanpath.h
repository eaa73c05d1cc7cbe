// foveal/io/scanpath.h — the scan-path picture of a recording: fixations as circles sized by
// duration over the screen, joined in order, on the faint trace of the raw gaze.
#pragma once

#include "foveal/gaze/fixation.h"
#include "foveal/util/image.h"

#include <string>

namespace foveal {

struct ScanpathStyle {
  int max_width = 1280;  // the picture is the screen scaled down to at most this width
  std::string title;     // drawn in the top-left corner
  bool numbers = true;   // number the fixations (the first 99)
};

// Draw and write a PNG (or anything OpenCV writes); throws Error if it cannot be written.
void write_scanpath(const Recording& recording, const FixationResult& fixations, const std::string& path, const ScanpathStyle& style = {});

// The simulated eye's scan path over the image it looked at (the paper's Figure 2): FAST corners
// as small dots, fixations as green circles joined in order, the first one marked.
void write_fixation_picture(const Image& linear_rgb, const std::vector<glm::vec2>& fixations, const std::vector<glm::vec2>& corners,
                            const std::string& path);

}  // namespace foveal
