// Reads glTF accessors into flat arrays, honouring byte strides, offsets, component types,
// normalization and sparse substitution. Every offset, stride and count from the file is checked
// with overflow-safe arithmetic against the buffer it points into, and the output is charged to
// the loader's budget before it is allocated. Errors throw std::runtime_error starting with
// `what` (e.g. "meshes[2].primitives[0] POSITION") and the accessor ("accessors[5]").
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <tiny_gltf.h>

#include "scenes/load_budget.hpp"

namespace shadow::scenes {

// `components` floats per element (e.g. 3 for POSITION). Float, or (normalized) integers; a
// float element that is NaN or infinite is an error.
std::vector<float> read_float_accessor(const tinygltf::Model& model, int accessor, int components,
                                       LoadBudget& budget, const std::string& what);

// SCALAR indices stored as unsigned byte, short or int.
std::vector<uint32_t> read_index_accessor(const tinygltf::Model& model, int accessor,
                                          LoadBudget& budget, const std::string& what);

}  // namespace shadow::scenes
