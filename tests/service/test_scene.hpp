// A small scene for service tests: a 20x20 ground quad at y = 0 and a unit box floating at
// y = 1..2 above the origin, lit by a sun, seen from above and behind.
#pragma once

#include <vector>

#include "shadow/v1/shadow.pb.h"
#include "wire/types.hpp"

namespace shadow::test {

std::shared_ptr<Scene> ground_and_box();

// The scene, a 320x240 camera, a sun and a 512^2 map; products as given.
RenderRequest small_request(std::vector<Product> products = {
                                Product::kShadowMap, Product::kVisibility, Product::kPosition});
// The same as wire bytes, small enough (64x48, 256^2) to send after every bad request.
v1::RenderRequest tiny_proto_request();

}  // namespace shadow::test
