// A straight occluder edge at height h over a ground plane, under a sun of angular diameter theta
// straight down (pcss_test.cpp; pixel_shape_test.cpp holds the GPU shape to it too). The ground's
// visibility across the edge is the fraction of the sun's disk not hidden: with
// s = x / (h tan(theta / 2)) in [-1, 1], f(s) = 1/2 + (s sqrt(1 - s^2) + asin s) / pi.
#pragma once

#include <cmath>
#include <memory>

#include "wire/types.hpp"

namespace shadow::testing {

// f(s): the visible share of the sun's disk at s half-widths from the edge's shadow.
inline double disk_fraction(double s) {
  if (s <= -1) return 0;
  if (s >= 1) return 1;
  return 0.5 + (s * std::sqrt(1 - s * s) + std::asin(s)) / M_PI;
}

// Ground 16 x 16 at y = 0; occluder over x < 0 (|z| < 8) at height h; a camera below the
// occluder, close to the edge, that sees the ground on both sides of it; PCSS 32/64 on a 2048
// map; visibility and position.
inline RenderRequest sun_edge_request(float h, float theta_deg, uint32_t width, uint32_t height) {
  auto scene = std::make_shared<Scene>();
  scene->meshes = {Mesh{{-8, 0, -8, 8, 0, -8, 8, 0, 8, -8, 0, 8}, {0, 2, 1, 0, 3, 2}, {}, {}},
                   Mesh{{-8, h, -8, 0, h, -8, 0, h, 8, -8, h, 8}, {0, 2, 1, 0, 3, 2}, {}, {}}};
  Instance occluder{1};
  occluder.receives_shadows = false;
  scene->instances = {Instance{0}, occluder};
  RenderRequest r;
  r.scene = scene;
  r.camera.eye = {1.5f * h, 0.6f * h, 0};
  r.camera.target = {-0.3f * h, 0, 0};
  r.camera.width = width;
  r.camera.height = height;
  r.camera.near = 0.05f;
  r.camera.far = 50.0f;
  r.lights[0].direction = {0, -1, 0};
  r.lights[0].size = theta_deg;
  r.shadow_map.size = 2048;
  r.filter.kind = FilterKind::kPcss;
  r.filter.pcss = {32, 64, true};
  r.products = {Product::kVisibility, Product::kPosition};
  return r;
}

}  // namespace shadow::testing
