#include "scenes/gltf_accessor.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace shadow::scenes {
namespace {

[[noreturn]] void fail(const std::string& what, const std::string& why) {
  throw std::runtime_error(what + ": " + why);
}

template <typename T>
T load(const unsigned char* p) {
  T value;
  std::memcpy(&value, p, sizeof value);  // glTF data is little-endian and may be unaligned
  return value;
}

// One component as a double; normalized integers map to [0,1] / [-1,1] as glTF specifies.
double component(const unsigned char* p, int type, bool normalized) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return load<float>(p);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return normalized ? load<uint8_t>(p) / 255.0 : load<uint8_t>(p);
    case TINYGLTF_COMPONENT_TYPE_BYTE:
      return normalized ? std::max(load<int8_t>(p) / 127.0, -1.0) : load<int8_t>(p);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return normalized ? load<uint16_t>(p) / 65535.0 : load<uint16_t>(p);
    case TINYGLTF_COMPONENT_TYPE_SHORT:
      return normalized ? std::max(load<int16_t>(p) / 32767.0, -1.0) : load<int16_t>(p);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
      return load<uint32_t>(p);
  }
  return 0.0;  // rejected before we get here
}

// An unsigned integer index component (unsigned byte, short or int).
uint32_t index_component(const unsigned char* p, int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return load<uint8_t>(p);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return load<uint16_t>(p);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
      return load<uint32_t>(p);
  }
  return 0;  // rejected before we get here
}

bool is_unsigned_index_type(int type) {
  return type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
         type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ||
         type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
}

// Where `count` elements of `element_size` bytes live: at(i) for every i < count lies inside the
// buffer, as locate() checked.
struct View {
  const unsigned char* base = nullptr;
  size_t stride = 0;
  const unsigned char* at(size_t i) const { return base + i * stride; }
};

View locate(const tinygltf::Model& model, int view_index, uint64_t byte_offset, uint64_t count,
            uint64_t element_size, bool allow_stride, const std::string& what) {
  if (view_index < 0 || static_cast<size_t>(view_index) >= model.bufferViews.size())
    fail(what, "bufferView " + std::to_string(view_index) + " does not exist");
  const auto& view = model.bufferViews[view_index];
  if (view.buffer < 0 || static_cast<size_t>(view.buffer) >= model.buffers.size())
    fail(what, "buffer " + std::to_string(view.buffer) + " does not exist");
  const auto& buffer = model.buffers[view.buffer];
  const auto view_end = checked_add(view.byteOffset, view.byteLength);
  if (!view_end || *view_end > buffer.data.size())
    fail(what, "bufferView " + std::to_string(view_index) + " (byteOffset " +
                   std::to_string(view.byteOffset) + ", byteLength " +
                   std::to_string(view.byteLength) + ") runs past the end of buffer " +
                   std::to_string(view.buffer) + " (" + std::to_string(buffer.data.size()) +
                   " bytes)");
  const uint64_t stride = (allow_stride && view.byteStride != 0) ? view.byteStride : element_size;
  if (stride < element_size)
    fail(what, "byteStride " + std::to_string(stride) + " is smaller than an element (" +
                   std::to_string(element_size) + " bytes)");
  if (count > 0) {
    // byte_offset + (count - 1) * stride + element_size <= byteLength, without wrapping.
    const auto span = checked_mul(count - 1, stride);
    const auto last = span ? checked_add(*span, element_size) : std::nullopt;
    const auto end = last ? checked_add(*last, byte_offset) : std::nullopt;
    if (!end || *end > view.byteLength)
      fail(what, std::to_string(count) + " elements from byteOffset " +
                     std::to_string(byte_offset) + " do not fit in bufferView " +
                     std::to_string(view_index) + " (" + std::to_string(view.byteLength) +
                     " bytes)");
  }
  return {buffer.data.data() + view.byteOffset + (count > 0 ? byte_offset : 0),
          static_cast<size_t>(stride)};
}

// Every component of every element as T, then the sparse substitutions. For T = float, float
// components must be finite.
template <typename T>
std::vector<T> read_components(const tinygltf::Model& model, int index, int components,
                               LoadBudget& budget, const std::string& owner) {
  const std::string what = owner + " accessors[" + std::to_string(index) + "]";
  if (index < 0 || static_cast<size_t>(index) >= model.accessors.size())
    fail(what, "does not exist");
  const auto& acc = model.accessors[index];
  const int have = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(acc.type));
  if (have != components)
    fail(what, "has " + std::to_string(have) + " components per element, expected " +
                   std::to_string(components));
  const int size = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(acc.componentType));
  if constexpr (std::is_same_v<T, uint32_t>) {
    if (!is_unsigned_index_type(acc.componentType))
      fail(what, "indices must be unsigned byte, short or int, not componentType " +
                     std::to_string(acc.componentType));
  } else if (size <= 0 || acc.componentType == TINYGLTF_COMPONENT_TYPE_INT ||
             acc.componentType == TINYGLTF_COMPONENT_TYPE_DOUBLE) {
    fail(what, "has unsupported componentType " + std::to_string(acc.componentType));
  }
  const uint64_t element = static_cast<uint64_t>(size) * components;
  const auto value = [&](const unsigned char* p) -> T {
    if constexpr (std::is_same_v<T, uint32_t>)
      return index_component(p, acc.componentType);
    else
      return static_cast<T>(component(p, acc.componentType, acc.normalized));
  };

  // `count` comes straight from the file: checked against the data it claims to read, and the
  // output charged to the budget, before anything is allocated.
  View v;
  if (acc.bufferView >= 0)
    v = locate(model, acc.bufferView, acc.byteOffset, acc.count, element, true, what);
  const auto total = checked_mul(acc.count, static_cast<uint64_t>(components));
  if (!total) fail(what, "count " + std::to_string(acc.count) + " is too large");
  budget.charge(*total, sizeof(T), what);
  std::vector<T> out(*total);  // no bufferView: zeros (the base of a sparse accessor)
  if (acc.bufferView >= 0) {
    for (size_t i = 0; i < acc.count; ++i)
      for (int c = 0; c < components; ++c) out[i * components + c] = value(v.at(i) + c * size);
  }

  if (acc.sparse.isSparse) {
    const auto& sp = acc.sparse;
    const std::string swhat = what + ".sparse";
    if (sp.count < 1 || static_cast<uint64_t>(sp.count) > acc.count)
      fail(swhat, "count " + std::to_string(sp.count) + " is not between 1 and the accessor's " +
                      std::to_string(acc.count) + " elements");
    if (!is_unsigned_index_type(sp.indices.componentType))
      fail(swhat + ".indices", "componentType " + std::to_string(sp.indices.componentType) +
                                   " is not unsigned byte, short or int");
    if (sp.indices.byteOffset < 0 || sp.values.byteOffset < 0)
      fail(swhat, "has a negative byteOffset");
    const auto n = static_cast<uint64_t>(sp.count);
    const int isize =
        tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(sp.indices.componentType));
    const View iv = locate(model, sp.indices.bufferView, sp.indices.byteOffset, n, isize, false,
                           swhat + ".indices");
    const View vv = locate(model, sp.values.bufferView, sp.values.byteOffset, n, element, false,
                           swhat + ".values");
    for (size_t k = 0; k < n; ++k) {
      const uint64_t target = index_component(iv.at(k), sp.indices.componentType);
      if (target >= acc.count)
        fail(swhat, "index " + std::to_string(target) + " out of range (" +
                        std::to_string(acc.count) + " elements)");
      for (int c = 0; c < components; ++c)
        out[target * components + c] = value(vv.at(k) + c * size);
    }
  }

  if constexpr (std::is_same_v<T, float>) {
    for (size_t i = 0; i < out.size(); ++i)
      if (!std::isfinite(out[i]))
        fail(what, "element " + std::to_string(i / components) + " is not finite");
  }
  return out;
}

}  // namespace

std::vector<float> read_float_accessor(const tinygltf::Model& model, int accessor, int components,
                                       LoadBudget& budget, const std::string& what) {
  return read_components<float>(model, accessor, components, budget, what);
}

std::vector<uint32_t> read_index_accessor(const tinygltf::Model& model, int accessor,
                                          LoadBudget& budget, const std::string& what) {
  return read_components<uint32_t>(model, accessor, 1, budget, what);
}

}  // namespace shadow::scenes
