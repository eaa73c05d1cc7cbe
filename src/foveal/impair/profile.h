// foveal/impair/profile.h — an eye as the user describes it: `--eye` presets joined with '+', or a
// JSON profile of one person with both eyes.
#pragma once

#include "foveal/impair/impairments.h"
#include "foveal/perception/eye.h"

#include <string>

namespace foveal {

struct EyeSpec {
  EyeParams eye;          // the optics (refraction, accommodation, pupil, glaucoma's saccades)
  Impairments impair;     // media, field, metamorphopsia, colour
  std::string source;     // the preset string or profile path
};

// A profile file (ending in .json) or presets joined with '+':
//   the optics: healthy, glaucoma[:S], myopia:-D, hyperopia:D, presbyopia:AGE, astigmatism:CYL[@AXIS]
//   age:YEARS                      the person's age (accommodation, glare, lens, field normals)
//   cataract[:S]                   S in [0, 1] (0.5): straylight × 10^S, glare and lens yellowing
//   glare                          the age-normal forward scatter alone
//   cvd:TYPE[:S]                   protan, deutan, tritan (severity S, 1), protanopia, deuteranopia,
//                                  tritanopia, achromatopsia (also without "cvd:")
//   field:FILE.csv | field:GRID:FILE | field:DEFECT   visual field (see field.h); field-view:OD|OS|both,
//                                  field-mode:contrast|blur|grey|fill
//   amd[:R[:A]]                    central scotoma of R° (5) with metamorphopsia of A° (0.3)
//   metamorphopsia:A[:R]           distortion up to A° within R° (6)
// Files are relative to the working directory. Throws Error naming the part.
EyeSpec parse_eye_spec(const std::string& text);

// A JSON profile; errors name the file and the JSON path (e.g. "p.json: /eyes/OD/refraction: …").
// Files it names are relative to the profile.
EyeSpec read_eye_profile(const std::string& path);
EyeSpec parse_eye_profile(const std::string& json_text, const std::string& name, const std::string& base_dir = ".");

}  // namespace foveal
