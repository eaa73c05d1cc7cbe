// foveal/impair/field_picture.h — a visual field as a picture: the loss map over ±30° (white = no
// loss, black = 30 dB or more), the meridians, and the view's test locations (both eyes: the
// integrated field) as dots coloured by their loss.
#pragma once

#include "foveal/impair/field.h"

#include <string>

namespace foveal {

// PNG, 600 × 600 (10 pixels per degree); throws Error naming the file when it cannot be written.
void write_field_picture(const VisualField& field, const FieldMap& map, const std::string& path);

}  // namespace foveal
