// Reads glTF accessors into flat arrays, honouring byte strides, offsets, component types,
// normalization and sparse substitution. Errors throw std::runtime_error naming the accessor.
#pragma once

#include <cstdint>
#include <vector>

#include <tiny_gltf.h>

namespace shadow::scenes {

// `components` floats per element (e.g. 3 for POSITION). Float, or (normalized) integers.
std::vector<float> read_float_accessor(const tinygltf::Model& model, int accessor, int components);

// SCALAR indices stored as unsigned byte, short or int.
std::vector<uint32_t> read_index_accessor(const tinygltf::Model& model, int accessor);

}  // namespace shadow::scenes
