// Proto <-> engine types for requests and scenes. Pure data conversion: byte-length and
// presence checks happen here (they only make sense on the wire); semantic validation (finite
// values, index ranges, sizes) is the engine's. Errors are shadow::InvalidArgument naming the
// proto field path, e.g. "scene.meshes[2].positions".
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "shadow/v1/shadow.pb.h"
#include "wire/types.hpp"

namespace shadow::convert {

// The scene a RenderRequest.scene_id names (the server's scene cache); throws NotFound.
using SceneLookup = std::function<std::shared_ptr<const Scene>(const std::string& scene_id)>;

// An absent shadow_map.size with TECHNIQUE_VIRTUAL (each clipmap level's virtual edge); with the
// other techniques absent stays ShadowMapSettings' 2048.
inline constexpr uint32_t kDefaultVirtualMapSize = 16384;

// Wire -> engine. Applies the proto's documented defaults for absent optional fields. A request
// by scene_id needs `lookup` (else InvalidArgument naming scene_id).
RenderRequest from_proto(const v1::RenderRequest& request, const SceneLookup& lookup = {});
// Errors are named "base.<field>" and "frames[i].<field>".
SequenceRequest from_proto(const v1::SequenceRequest& request, const SceneLookup& lookup = {});
std::shared_ptr<Scene> from_proto(const v1::Scene& scene);
Camera from_proto(const v1::Camera& camera);
Light from_proto(const v1::Light& light, const std::string& field = "light");
// TECHNIQUE_UNSPECIFIED becomes kDefault, resolved per light by the engine (kCube for a point
// light, else kUniform). An absent size is 2048, or kDefaultVirtualMapSize with TECHNIQUE_VIRTUAL.
ShadowMapSettings from_proto(const v1::ShadowMapSettings& settings);
Filter from_proto(const v1::Filter& filter);
// `field` names the oneof member ("filter.csm") for errors.
CsmSettings from_proto(const v1::CsmSettings& settings, const std::string& field);

// Engine -> wire, for clients. Every optional field is written explicitly.
v1::RenderRequest to_proto(const RenderRequest& request);
v1::SequenceRequest to_proto(const SequenceRequest& request);
v1::Scene to_proto(const Scene& scene);
v1::Mesh to_proto(const Mesh& mesh);
v1::Camera to_proto(const Camera& camera);
v1::Light to_proto(const Light& light);
v1::ShadowMapSettings to_proto(const ShadowMapSettings& settings);
v1::Filter to_proto(const Filter& filter);
v1::CsmSettings to_proto(const CsmSettings& settings);

// Small pieces, shared with the result conversion.
v1::Vec3 to_proto(const glm::vec3& v);
v1::Mat4 to_proto(const glm::mat4& m);
glm::vec3 from_proto(const v1::Vec3& v);
// `field` names the matrix in errors (it must hold exactly 16 values).
glm::mat4 from_proto(const v1::Mat4& m, const std::string& field);

// Sets the filter's kind (its oneof) to `kind`, keeping the settings already there when it is
// that kind, else with empty settings (the proto's defaults).
void set_kind(v1::Filter& filter, FilterKind kind);

v1::Technique to_proto(Technique technique);

v1::Product to_proto(Product product);
// Throws InvalidArgument(field) for PRODUCT_UNSPECIFIED or an unknown value.
Product from_proto(v1::Product product, const std::string& field);

// CHUNK_COMPRESSION_UNSPECIFIED is kNone; throws InvalidArgument(field) for an unknown value.
ChunkCompression from_proto(v1::ChunkCompression compression, const std::string& field);

}  // namespace shadow::convert
