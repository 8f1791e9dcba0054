#include "scenes/gltf_accessor.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

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

// Where `count` elements of `element_size` bytes live; strided and bounds-checked.
struct View {
  const unsigned char* base = nullptr;
  size_t stride = 0;
  const unsigned char* at(size_t i) const { return base + i * stride; }
};

View locate(const tinygltf::Model& model, int view_index, size_t byte_offset, size_t count,
            size_t element_size, bool allow_stride, const std::string& what) {
  if (view_index < 0 || view_index >= static_cast<int>(model.bufferViews.size()))
    fail(what, "bufferView " + std::to_string(view_index) + " does not exist");
  const auto& view = model.bufferViews[view_index];
  if (view.buffer < 0 || view.buffer >= static_cast<int>(model.buffers.size()))
    fail(what, "buffer " + std::to_string(view.buffer) + " does not exist");
  const auto& buffer = model.buffers[view.buffer];
  if (view.byteOffset + view.byteLength > buffer.data.size())
    fail(what, "bufferView " + std::to_string(view_index) + " runs past the end of buffer " +
                   std::to_string(view.buffer) + " (" + std::to_string(buffer.data.size()) +
                   " bytes)");
  const size_t stride = (allow_stride && view.byteStride != 0) ? view.byteStride : element_size;
  if (stride < element_size)
    fail(what, "byteStride " + std::to_string(stride) + " is smaller than an element (" +
                   std::to_string(element_size) + " bytes)");
  if (count > 0 && byte_offset + (count - 1) * stride + element_size > view.byteLength)
    fail(what, std::to_string(count) + " elements do not fit in bufferView " +
                   std::to_string(view_index) + " (" + std::to_string(view.byteLength) + " bytes)");
  return {buffer.data.data() + view.byteOffset + byte_offset, stride};
}

const tinygltf::Accessor& accessor_at(const tinygltf::Model& model, int index,
                                      const std::string& what) {
  if (index < 0 || index >= static_cast<int>(model.accessors.size())) fail(what, "does not exist");
  return model.accessors[index];
}

// Reads every component of every element as double, then applies sparse substitutions.
std::vector<double> read_components(const tinygltf::Model& model, int index, int components,
                                    const std::string& what) {
  const auto& acc = accessor_at(model, index, what);
  const int have = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(acc.type));
  if (have != components)
    fail(what, "has " + std::to_string(have) + " components per element, expected " +
                   std::to_string(components));
  const int size = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(acc.componentType));
  if (size <= 0 || acc.componentType == TINYGLTF_COMPONENT_TYPE_INT ||
      acc.componentType == TINYGLTF_COMPONENT_TYPE_DOUBLE)
    fail(what, "has unsupported componentType " + std::to_string(acc.componentType));
  const size_t element = static_cast<size_t>(size) * components;

  std::vector<double> out(acc.count * components, 0.0);  // no bufferView: zeros (sparse base)
  if (acc.bufferView >= 0) {
    const View v = locate(model, acc.bufferView, acc.byteOffset, acc.count, element, true, what);
    for (size_t i = 0; i < acc.count; ++i)
      for (int c = 0; c < components; ++c)
        out[i * components + c] = component(v.at(i) + c * size, acc.componentType, acc.normalized);
  }

  if (acc.sparse.isSparse) {
    const auto& sp = acc.sparse;
    const std::string swhat = what + ".sparse";
    const size_t n = static_cast<size_t>(std::max(sp.count, 0));
    const int isize =
        tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(sp.indices.componentType));
    if (isize <= 0 || sp.indices.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT)
      fail(swhat, "has unsupported index componentType");
    const View iv = locate(model, sp.indices.bufferView, sp.indices.byteOffset, n, isize, false,
                           swhat + ".indices");
    const View vv = locate(model, sp.values.bufferView, sp.values.byteOffset, n, element, false,
                           swhat + ".values");
    for (size_t k = 0; k < n; ++k) {
      const auto target = static_cast<size_t>(component(iv.at(k), sp.indices.componentType, false));
      if (target >= acc.count)
        fail(swhat, "index " + std::to_string(target) + " out of range (" +
                        std::to_string(acc.count) + " elements)");
      for (int c = 0; c < components; ++c)
        out[target * components + c] =
            component(vv.at(k) + c * size, acc.componentType, acc.normalized);
    }
  }
  return out;
}

}  // namespace

std::vector<float> read_float_accessor(const tinygltf::Model& model, int accessor, int components) {
  const std::string what = "accessors[" + std::to_string(accessor) + "]";
  const auto values = read_components(model, accessor, components, what);
  return std::vector<float>(values.begin(), values.end());
}

std::vector<uint32_t> read_index_accessor(const tinygltf::Model& model, int accessor) {
  const std::string what = "accessors[" + std::to_string(accessor) + "]";
  const int type = accessor_at(model, accessor, what).componentType;
  if (type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
      type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
      type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
    fail(what,
         "indices must be unsigned byte, short or int, not componentType " + std::to_string(type));
  const auto values = read_components(model, accessor, 1, what);
  return std::vector<uint32_t>(values.begin(), values.end());
}

}  // namespace shadow::scenes
