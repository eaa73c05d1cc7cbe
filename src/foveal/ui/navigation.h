// foveal/ui/navigation.h — orbit and fly camera navigation for the viewer (mouse deltas in pixels).
#pragma once

#include "foveal/scene/scene.h"

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <cmath>

namespace foveal {

// Rotate v about a unit axis by an angle (radians).
inline glm::vec3 rotate_about(glm::vec3 v, glm::vec3 axis, float angle) {
  return glm::vec3(glm::rotate(glm::mat4(1.0f), angle, glm::normalize(axis)) * glm::vec4(v, 0.0f));
}

// Orbit (the eye circles the look point, the wheel dollies towards it) and fly (the look point
// circles the eye, W/A/S/D/Q/E move both) navigation on a Camera.
struct Navigator {
  bool fly = false;
  float speed = 1.0f;  // fly: scene units per second (set from the scene's size)

  void rotate_view(Camera& c, float dx, float dy) const {
    const glm::vec3 up = glm::normalize(c.up);
    if (!fly) {  // orbit: the eye moves around the look point
      glm::vec3 offset = c.eye - c.look;
      offset = rotate_about(offset, up, -dx * 0.006f);
      const glm::vec3 right = glm::cross(glm::normalize(offset), up);
      const glm::vec3 pitched = rotate_about(offset, right, dy * 0.006f);
      if (glm::length(glm::cross(glm::normalize(pitched), up)) > 0.05f) offset = pitched;  // never over the pole
      c.eye = c.look + offset;
    } else {  // fly: the look point moves around the eye
      glm::vec3 dir = c.look - c.eye;
      dir = rotate_about(dir, up, -dx * 0.004f);
      const glm::vec3 right = glm::cross(glm::normalize(dir), up);
      const glm::vec3 pitched = rotate_about(dir, right, -dy * 0.004f);
      if (glm::length(glm::cross(glm::normalize(pitched), up)) > 0.05f) dir = pitched;
      c.look = c.eye + dir;
    }
  }
  void pan(Camera& c, float dx, float dy) const {
    const glm::vec3 f = c.look - c.eye;
    const glm::vec3 right = glm::normalize(glm::cross(f, c.up)), up = glm::normalize(glm::cross(right, f));
    const glm::vec3 d = (-dx * right + dy * up) * glm::length(f) * 0.0015f;
    c.eye += d;
    c.look += d;
  }
  void dolly(Camera& c, float wheel) const {
    const glm::vec3 f = c.look - c.eye;
    const float factor = std::pow(0.9f, wheel);
    if (!fly) {
      if (glm::length(f) * factor > speed * 1e-4f) c.eye = c.look - f * factor;  // the eye never reaches the look point
    } else {
      const glm::vec3 step = glm::normalize(f) * speed * 0.25f * wheel;
      c.eye += step;
      c.look += step;
    }
  }
  void move(Camera& c, glm::vec3 local, float seconds) const {  // local: right, up, forward
    const glm::vec3 f = glm::normalize(c.look - c.eye), right = glm::normalize(glm::cross(f, c.up)), up = glm::normalize(c.up);
    const glm::vec3 d = (local.x * right + local.y * up + local.z * f) * speed * seconds;
    c.eye += d;
    c.look += d;
  }
};

}  // namespace foveal
