// Orbit and fly navigation: what each gesture keeps and what it changes.
#include "foveal/ui/navigation.h"

#include <gtest/gtest.h>

namespace foveal {
namespace {

Camera start() {
  Camera c;
  c.eye = {0, 1, 5};
  c.look = {0, 1, 0};
  return c;
}

TEST(Navigator, OrbitCirclesTheLookPointAndNeverCrossesThePole) {
  Navigator nav;
  Camera c = start();
  nav.rotate_view(c, static_cast<float>(3.14159265 / 0.006), 0);  // half a turn about the up axis
  EXPECT_EQ(c.look, start().look);
  EXPECT_NEAR(glm::length(c.eye - c.look), 5, 1e-4);
  EXPECT_NEAR(c.eye.z, -5, 1e-3);                           // now behind the look point
  for (int i = 0; i < 100; ++i) nav.rotate_view(c, 0, 50);  // drag far upwards
  EXPECT_NEAR(glm::length(c.eye - c.look), 5, 1e-3);
  EXPECT_GT(glm::length(glm::cross(glm::normalize(c.eye - c.look), c.up)), 0.04f);  // stopped short of straight above
  Camera d = start();
  nav.dolly(d, 1);
  EXPECT_NEAR(glm::length(d.eye - d.look), 4.5, 1e-5);
  for (int i = 0; i < 2000; ++i) nav.dolly(d, 1);  // a long zoom in: the eye stops short of the look point
  EXPECT_GT(glm::length(d.eye - d.look), nav.speed * 1e-4f * 0.9f);
  EXPECT_LT(glm::length(d.eye - d.look), nav.speed * 1e-4f / 0.9f + 1e-6f);
}

TEST(Navigator, FlyMovesTheEyeAndTurnsTheLook) {
  Navigator nav;
  nav.fly = true;
  nav.speed = 2;
  Camera c = start();
  nav.move(c, {0, 0, 1}, 0.5f);  // forward for half a second
  EXPECT_NEAR(c.eye.z, 4, 1e-5);
  EXPECT_NEAR(c.look.z, -1, 1e-5);
  nav.move(c, {1, 0, 0}, 0.5f);  // right
  EXPECT_NEAR(c.eye.x, 1, 1e-5);
  const glm::vec3 eye = c.eye;
  nav.rotate_view(c, 100, 0);  // look around: the eye stays
  EXPECT_EQ(c.eye, eye);
  EXPECT_NEAR(glm::length(c.look - c.eye), 5, 1e-4);
  EXPECT_GT(std::abs(c.look.x - eye.x), 0.5f);
  Camera p = start();
  nav.pan(p, 10, 0);  // pan keeps the view direction
  EXPECT_NEAR(glm::length(glm::normalize(p.look - p.eye) - glm::normalize(start().look - start().eye)), 0, 1e-6);
  EXPECT_LT(p.eye.x, 0);
}

}  // namespace
}  // namespace foveal
