// foveal/impair/profile.h — an eye as the user describes it: `--eye` presets joined with '+', or a
// JSON profile of one person with both eyes.
#pragma once

#include "foveal/impair/impairments.h"
#include "foveal/perception/eye.h"

#include <nlohmann/json_fwd.hpp>

#include <optional>
#include <string>

namespace foveal {

struct EyeSpec {
  EyeParams eye;       // the optics (refraction, accommodation, pupil, glaucoma's saccades)
  Impairments impair;  // media, field, metamorphopsia, colour
  std::string source;  // the preset string or profile path
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

// What a user states explicitly about an eye besides its presets or profile; unset = not given.
struct EyeOverrides {
  std::optional<double> pupil_diameter_mm;  // A, mm (a profile's "pupil_mm")
  std::optional<double> image_distance_mm;  // I, lens to retina, mm
};

// The one rule for an eye, the same in simulate, view, perceive, bench vision and Python: `spec`
// (presets joined with '+', or a profile .json) gives the eye, and every override that is given
// replaces what the spec says — whatever its value, the default's included. Where neither says,
// EyeParams' defaults hold. So: explicit option > profile or presets > default. Validated (errors
// name the parameter, e.g. "pupil_diameter_mm: …").
EyeSpec resolve_eye(const std::string& spec, const EyeOverrides& overrides = {});

// The optics of an eye as written to stats files: preset, pupil_mm, image_distance_mm,
// refraction_d, cylinder_d, axis_deg, age_years, glaucoma.
nlohmann::json optics_json(const EyeParams& eye);

}  // namespace foveal
