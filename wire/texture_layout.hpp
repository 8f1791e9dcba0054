// A texture's layout on the Render stream: its byte size and its cube faces. The slicer
// (wire/result_slicer.hpp, the server) and the assembler (wire/result_assembler.hpp, the
// client) hold a texture to the same rules.
#pragma once

#include <cstdint>
#include <string>

#include "wire/types.hpp"

namespace shadow::convert {

// width * height * channels * faces * value_bytes(); false if that overflows 64 bits.
bool texture_bytes(const Texture& texture, uint64_t* out);

// What is wrong with a texture's cube faces, starting with `field` (the cube_faces field), or ""
// when they are consistent: one distinct named face (+x .. -z) per face of data, at most six.
// A texture that is not a cube (no cube_faces, one face) is consistent.
std::string cube_faces_problem(const Texture& texture, const std::string& field);

}  // namespace shadow::convert
