#include "wire/convert.hpp"

#include <algorithm>
#include <string>
#include <vector>

#include "wire/errors.hpp"
#include "wire/little_endian.hpp"
#include "wire/names.hpp"

namespace shadow::convert {
namespace {

std::string indexed(const std::string& field, size_t i) {
  return field + "[" + std::to_string(i) + "]";
}

// Decodes a packed little-endian array of 4-byte elements whose byte length must be a multiple
// of `group` elements (3 for xyz, 2 for uv, 3 for a triangle).
template <class T>
std::vector<T> decode(const std::string& bytes, size_t group, const std::string& field,
                      const char* shape) {
  const size_t group_bytes = group * sizeof(T);
  if (bytes.size() % group_bytes != 0) {
    throw InvalidArgument(field, "byte length " + std::to_string(bytes.size()) +
                                     " is not a multiple of " + std::to_string(group_bytes) + " (" +
                                     shape + ", little-endian)");
  }
  std::vector<T> out(bytes.size() / sizeof(T));
  le_to_host(bytes.data(), out.size(), out.data());
  return out;
}

template <class T>
std::string encode(const std::vector<T>& values) {
  std::string bytes(values.size() * sizeof(T), '\0');
  host_to_le(values.data(), values.size(), bytes.data());
  return bytes;
}

Mesh mesh_from_proto(const v1::Mesh& m, const std::string& field) {
  Mesh mesh;
  mesh.positions = decode<float>(m.positions(), 3, field + ".positions", "float32 [n][3]");
  mesh.indices = decode<uint32_t>(m.indices(), 3, field + ".indices", "uint32 [t][3]");
  mesh.normals = decode<float>(m.normals(), 3, field + ".normals", "float32 [n][3]");
  mesh.uvs = decode<float>(m.uvs(), 2, field + ".uvs", "float32 [n][2]");
  // Optional attributes are all-or-nothing: one per vertex.
  const size_t n = mesh.vertex_count();
  if (!mesh.normals.empty() && mesh.normals.size() != 3 * n) {
    throw InvalidArgument(field + ".normals", "holds " + std::to_string(mesh.normals.size() / 3) +
                                                  " normals for " + std::to_string(n) +
                                                  " vertices; send one per vertex or none");
  }
  if (!mesh.uvs.empty() && mesh.uvs.size() != 2 * n) {
    throw InvalidArgument(field + ".uvs", "holds " + std::to_string(mesh.uvs.size() / 2) +
                                              " uvs for " + std::to_string(n) +
                                              " vertices; send one per vertex or none");
  }
  return mesh;
}

glm::vec3 required_vec3(bool present, const v1::Vec3& v, const std::string& field) {
  if (!present) throw InvalidArgument(field, "required");
  return from_proto(v);
}

// A value of an enum or oneof case from the wire, through its name table; InvalidArgument(field)
// naming the number when the table has no row for it.
template <class Value, class Proto>
Value known(const names::Table<Value, Proto>& table, Proto proto, const std::string& field) {
  if (const std::optional<Value> value = table.from_proto(proto)) return *value;
  throw InvalidArgument(field, table.unknown_proto(proto));
}

}  // namespace

glm::vec3 from_proto(const v1::Vec3& v) {
  return {v.x(), v.y(), v.z()};
}

v1::Vec3 to_proto(const glm::vec3& v) {
  v1::Vec3 out;
  out.set_x(v.x);
  out.set_y(v.y);
  out.set_z(v.z);
  return out;
}

glm::mat4 from_proto(const v1::Mat4& m, const std::string& field) {
  if (m.m_size() != 16) {
    throw InvalidArgument(field + ".m",
                          "holds " + std::to_string(m.m_size()) + " values, expected 16");
  }
  glm::mat4 out;
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) out[c][r] = m.m(4 * c + r);
  }
  return out;
}

v1::Mat4 to_proto(const glm::mat4& m) {
  v1::Mat4 out;
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) out.add_m(m[c][r]);
  }
  return out;
}

Product from_proto(v1::Product product, const std::string& field) {
  if (product == v1::PRODUCT_UNSPECIFIED)
    throw InvalidArgument(field, "PRODUCT_UNSPECIFIED is not a product");
  return known(names::kProducts, product, field);
}

v1::Product to_proto(Product product) {
  return names::kProducts.to_proto(product);
}

void set_kind(v1::Filter& filter, FilterKind kind) {
  // A oneof's case is its member's field number.
  const auto* member =
      v1::Filter::descriptor()->FindFieldByNumber(names::kFilterKinds.to_proto(kind));
  filter.GetReflection()->MutableMessage(&filter, member);
}

std::shared_ptr<Scene> from_proto(const v1::Scene& s) {
  auto scene = std::make_shared<Scene>();
  scene->meshes.reserve(s.meshes_size());
  for (int i = 0; i < s.meshes_size(); ++i) {
    scene->meshes.push_back(mesh_from_proto(s.meshes(i), indexed("scene.meshes", i)));
  }
  scene->instances.reserve(s.instances_size());
  for (int j = 0; j < s.instances_size(); ++j) {
    const v1::Instance& in = s.instances(j);
    Instance instance;
    instance.mesh = in.mesh();
    if (in.has_transform()) {
      instance.transform = from_proto(in.transform(), indexed("scene.instances", j) + ".transform");
    }
    instance.casts_shadows = in.has_casts_shadows() ? in.casts_shadows() : true;
    instance.receives_shadows = in.has_receives_shadows() ? in.receives_shadows() : true;
    if (in.has_receiver_class()) instance.receiver_class = in.receiver_class();
    scene->instances.push_back(instance);
  }
  return scene;
}

Camera from_proto(const v1::Camera& c) {
  Camera camera;
  camera.eye = required_vec3(c.has_eye(), c.eye(), "camera.eye");
  camera.target = required_vec3(c.has_target(), c.target(), "camera.target");
  camera.up = c.has_up() ? from_proto(c.up()) : glm::vec3(0.0f, 1.0f, 0.0f);
  camera.fov_deg = c.has_fov_deg() ? c.fov_deg() : 60.0f;
  camera.width = c.width();
  camera.height = c.height();
  camera.near = c.has_near() ? c.near() : 0.1f;
  camera.far = c.has_far() ? c.far() : 1000.0f;
  return camera;
}

Light from_proto(const v1::Light& l, const std::string& f) {
  if (l.kind_case() == v1::Light::KIND_NOT_SET)
    throw InvalidArgument(f, "one of directional, spot or point is required");
  Light light;
  light.size = l.size();
  light.type = known(names::kLightTypes, l.kind_case(), f);
  switch (light.type) {
    case LightType::kDirectional:
      light.direction = required_vec3(l.directional().has_direction(), l.directional().direction(),
                                      f + ".directional.direction");
      break;
    case LightType::kSpot:
      light.position =
          required_vec3(l.spot().has_position(), l.spot().position(), f + ".spot.position");
      light.direction =
          required_vec3(l.spot().has_direction(), l.spot().direction(), f + ".spot.direction");
      light.cone_angle_deg = l.spot().cone_angle_deg();
      break;
    case LightType::kPoint:
      light.position =
          required_vec3(l.point().has_position(), l.point().position(), f + ".point.position");
      break;
  }
  return light;
}

ChunkCompression from_proto(v1::ChunkCompression compression, const std::string& field) {
  if (compression == v1::CHUNK_COMPRESSION_UNSPECIFIED) return ChunkCompression::kNone;
  return known(names::kChunkCompressions, compression, field);
}

v1::Technique to_proto(Technique technique) {
  if (technique == Technique::kDefault) return v1::TECHNIQUE_UNSPECIFIED;  // not a table row
  return names::kTechniques.to_proto(technique);
}

ShadowMapSettings from_proto(const v1::ShadowMapSettings& s) {
  ShadowMapSettings settings;
  // Unspecified = kDefault, resolved per light by the engine.
  if (s.technique() != v1::TECHNIQUE_UNSPECIFIED)
    settings.technique = known(names::kTechniques, s.technique(), "shadow_map.technique");
  // Absent: 2048, or a virtual level's 16384 (its pages cost only where pixels read them).
  if (s.has_size())
    settings.size = s.size();
  else if (settings.technique == Technique::kVirtual)
    settings.size = kDefaultVirtualMapSize;
  if (s.has_bias_constant()) settings.bias_constant = s.bias_constant();
  if (s.has_bias_slope()) settings.bias_slope = s.bias_slope();
  if (s.psm_casters() != v1::PSM_CASTERS_UNSPECIFIED)  // else kInverseProjection
    settings.psm.casters = known(names::kPsmCasters, s.psm_casters(), "shadow_map.psm_casters");
  if (s.psm_near() != v1::PSM_NEAR_UNSPECIFIED)  // else kReceivers
    settings.psm.near = known(names::kPsmNear, s.psm_near(), "shadow_map.psm_near");
  if (s.has_psm_virtual_slide()) settings.psm.virtual_slide = s.psm_virtual_slide();
  if (s.has_lispsm_n()) settings.lispsm.n = s.lispsm_n();
  if (s.fit() != v1::MAP_FIT_UNSPECIFIED)  // else kView
    settings.fit = known(names::kMapFits, s.fit(), "shadow_map.fit");
  if (s.has_bias_world_constant()) settings.bias_world_constant = s.bias_world_constant();
  if (s.has_bias_world_texel()) settings.bias_world_texel = s.bias_world_texel();
  if (s.has_virtual_lod_bias()) settings.virtual_lod_bias = s.virtual_lod_bias();
  if (s.has_virtual_pool_pages()) settings.virtual_pool_pages = s.virtual_pool_pages();
  settings.virtual_refuse_coarsening = s.virtual_refuse_coarsening();
  return settings;
}

CsmSettings from_proto(const v1::CsmSettings& c, const std::string& field) {
  CsmSettings s;
  if (c.has_terms()) s.terms = c.terms();
  if (c.storage() != v1::CSM_STORAGE_UNSPECIFIED)  // else float32
    s.storage = known(names::kCsmStorages, c.storage(), field + ".storage");
  if (c.has_window()) s.window = c.window();
  if (c.has_damping()) s.damping = c.damping();
  if (c.has_depth_offset()) s.depth_offset = c.depth_offset();
  if (c.has_scale()) s.scale = c.scale();
  if (c.lookup() != v1::CSM_LOOKUP_UNSPECIFIED)  // else mips
    s.lookup = known(names::kCsmLookups, c.lookup(), field + ".lookup");
  return s;
}

v1::CsmSettings to_proto(const CsmSettings& s) {
  v1::CsmSettings c;
  c.set_terms(s.terms);
  c.set_storage(names::kCsmStorages.to_proto(s.storage));
  c.set_window(s.window);
  c.set_damping(s.damping);
  c.set_depth_offset(s.depth_offset);
  c.set_scale(s.scale);
  c.set_lookup(names::kCsmLookups.to_proto(s.lookup));
  return c;
}

Filter from_proto(const v1::Filter& f) {
  Filter filter;
  if (f.kind_case() != v1::Filter::KIND_NOT_SET)  // else kHard
    filter.kind = known(names::kFilterKinds, f.kind_case(), "filter");
  switch (filter.kind) {
    case FilterKind::kHard:
    case FilterKind::kPcf2x2:
      break;
    case FilterKind::kPoisson: {
      const v1::PoissonSettings& p = f.poisson();
      if (p.has_taps()) filter.poisson.taps = p.taps();
      if (p.has_radius()) filter.poisson.radius = p.radius();
      if (p.has_rotate()) filter.poisson.rotate = p.rotate();
      break;
    }
    case FilterKind::kPcss: {
      const v1::PcssSettings& p = f.pcss();
      if (p.has_blocker_samples()) filter.pcss.blocker_samples = p.blocker_samples();
      if (p.has_filter_samples()) filter.pcss.filter_samples = p.filter_samples();
      if (p.has_rotate()) filter.pcss.rotate = p.rotate();
      break;
    }
    case FilterKind::kBlur: {
      const v1::BlurSettings& b = f.blur();
      if (b.has_radius()) filter.blur.radius = b.radius();
      if (b.has_passes()) filter.blur.passes = b.passes();
      break;
    }
    case FilterKind::kCsm:
      filter.csm = from_proto(f.csm(), "filter.csm");
      break;
    case FilterKind::kPcssCsm:
      filter.csm = from_proto(f.pcss_csm(), "filter.pcss_csm");
      break;
    case FilterKind::kAtlasSat:
    case FilterKind::kAtlasMip: {
      const v1::AtlasFilterSettings& a =
          filter.kind == FilterKind::kAtlasSat ? f.atlas_sat() : f.atlas_mip();
      if (a.has_blocker_samples()) filter.pcss.blocker_samples = a.blocker_samples();
      if (a.has_rotate()) filter.pcss.rotate = a.rotate();
      break;
    }
  }
  return filter;
}

v1::Filter to_proto(const Filter& filter) {
  v1::Filter out;
  set_kind(out, filter.kind);
  switch (filter.kind) {
    case FilterKind::kHard:
    case FilterKind::kPcf2x2:
      break;
    case FilterKind::kPoisson: {
      v1::PoissonSettings& p = *out.mutable_poisson();
      p.set_taps(filter.poisson.taps);
      p.set_radius(filter.poisson.radius);
      p.set_rotate(filter.poisson.rotate);
      break;
    }
    case FilterKind::kPcss: {
      v1::PcssSettings& p = *out.mutable_pcss();
      p.set_blocker_samples(filter.pcss.blocker_samples);
      p.set_filter_samples(filter.pcss.filter_samples);
      p.set_rotate(filter.pcss.rotate);
      break;
    }
    case FilterKind::kBlur: {
      v1::BlurSettings& b = *out.mutable_blur();
      b.set_radius(filter.blur.radius);
      b.set_passes(filter.blur.passes);
      break;
    }
    case FilterKind::kCsm:
      *out.mutable_csm() = to_proto(filter.csm);
      break;
    case FilterKind::kPcssCsm:
      *out.mutable_pcss_csm() = to_proto(filter.csm);
      break;
    case FilterKind::kAtlasSat:
    case FilterKind::kAtlasMip: {
      v1::AtlasFilterSettings& a = filter.kind == FilterKind::kAtlasSat ? *out.mutable_atlas_sat()
                                                                        : *out.mutable_atlas_mip();
      a.set_blocker_samples(filter.pcss.blocker_samples);
      a.set_rotate(filter.pcss.rotate);
      break;
    }
  }
  return out;
}

RenderRequest from_proto(const v1::RenderRequest& r, const SceneLookup& lookup) {
  RenderRequest request;
  if (!r.has_camera()) throw InvalidArgument("camera", "required");
  // An empty list is the engine's to refuse (a POSITION-only request needs no light).
  request.lights.clear();
  for (int i = 0; i < r.lights_size(); ++i)
    request.lights.push_back(from_proto(r.lights(i), indexed("lights", i)));
  request.camera = from_proto(r.camera());
  request.shadow_map = from_proto(r.shadow_map());
  request.filter = from_proto(r.filter());
  if (r.products_size() == 0) {
    throw InvalidArgument("products", "at least one product is required");
  }
  for (int i = 0; i < r.products_size(); ++i) {
    request.products.push_back(from_proto(r.products(i), indexed("products", i)));
  }
  if (r.atlas().has_tile_size()) request.atlas.tile = r.atlas().tile_size();
  if (r.atlas().has_texel_world_size())
    request.atlas.texel_world_size = r.atlas().texel_world_size();
  // An unspecified fit is the one the request needs: the shadow atlas covers every receiver, so
  // its maps are fitted to the scene. A fit the client named stays (the engine refuses VIEW).
  if (r.shadow_map().fit() == v1::MAP_FIT_UNSPECIFIED) {
    const bool atlas = request.filter.kind == FilterKind::kAtlasSat ||
                       request.filter.kind == FilterKind::kAtlasMip ||
                       std::any_of(request.products.begin(), request.products.end(), [](Product p) {
                         return p == Product::kShadowAtlas || p == Product::kShadowAtlasMips ||
                                p == Product::kShadowAtlasSat;
                       });
    if (atlas) request.shadow_map.fit = MapFit::kScene;
  }
  if (r.atlas().has_gutter()) request.atlas.gutter = r.atlas().gutter();
  if (r.atlas().has_generate_uvs()) request.atlas.generate_uvs = r.atlas().generate_uvs();
  if (r.has_quality()) {
    // The goal picks these: a client's own would be silently replaced.
    if (r.shadow_map().has_size())
      throw InvalidArgument("shadow_map.size",
                            "is picked by the quality goal: leave it absent, or drop quality");
    switch (r.quality().goal_case()) {
      case v1::Quality::kMaxError:
        request.quality = {Quality::Goal::kMaxError, r.quality().max_error()};
        break;
      case v1::Quality::kMaxDeviceMs:
        request.quality = {Quality::Goal::kMaxDeviceMs, r.quality().max_device_ms()};
        break;
      case v1::Quality::GOAL_NOT_SET:
        throw InvalidArgument("quality", "set max_error or max_device_ms");
    }
  }
  switch (r.pixel_format()) {
    case v1::PIXEL_FORMAT_UNSPECIFIED:
    case v1::PIXEL_FORMAT_FLOAT32:
      break;
    case v1::PIXEL_FORMAT_FLOAT16:
      request.output_format = PixelFormat::kFloat16;
      break;
    case v1::PIXEL_FORMAT_FLOAT64:
      throw InvalidArgument("pixel_format", "FLOAT64 is for summed-area tables only");
    default:
      throw InvalidArgument("pixel_format", names::kPixelFormats.unknown_proto(r.pixel_format()));
  }
  // Scene last: it is the expensive part and the cheap checks above should fail first.
  if (r.scene_source_case() != v1::RenderRequest::kSceneId) {
    request.scene = from_proto(r.scene());
  } else if (lookup) {
    request.scene = lookup(r.scene_id());
    request.scene_held = true;
  } else {
    throw InvalidArgument("scene_id", "scenes by id are not accepted here: send the scene inline");
  }
  return request;
}

SequenceRequest from_proto(const v1::SequenceRequest& r, const SceneLookup& lookup) {
  SequenceRequest sequence;
  with_field_renamed([&] { sequence.base = from_proto(r.base(), lookup); },
                     [](const std::string& field) { return "base." + field; });
  for (int i = 0; i < r.frames_size(); ++i) {
    const v1::Frame& in = r.frames(i);
    const std::string f = indexed("frames", i);
    Frame& frame = sequence.frames.emplace_back();
    if (in.has_camera())
      with_field_renamed([&] { frame.camera = from_proto(in.camera()); },
                         [&](const std::string& field) { return f + "." + field; });
    if (in.lights_size() > 0) {
      frame.lights.emplace();
      for (int k = 0; k < in.lights_size(); ++k)
        frame.lights->push_back(from_proto(in.lights(k), f + "." + indexed("lights", k)));
    }
    for (int k = 0; k < in.transforms_size(); ++k) {
      const std::string t = f + "." + indexed("transforms", k);
      frame.transforms.push_back({in.transforms(k).instance(),
                                  from_proto(in.transforms(k).transform(), t + ".transform")});
    }
  }
  return sequence;
}

v1::SequenceRequest to_proto(const SequenceRequest& sequence) {
  v1::SequenceRequest out;
  *out.mutable_base() = to_proto(sequence.base);
  for (const Frame& frame : sequence.frames) {
    v1::Frame& f = *out.add_frames();
    if (frame.camera) *f.mutable_camera() = to_proto(*frame.camera);
    if (frame.lights)
      for (const Light& light : *frame.lights) *f.add_lights() = to_proto(light);
    for (const InstanceTransform& t : frame.transforms) {
      v1::InstanceTransform& o = *f.add_transforms();
      o.set_instance(t.instance);
      *o.mutable_transform() = to_proto(t.transform);
    }
  }
  return out;
}

v1::Mesh to_proto(const Mesh& mesh) {
  v1::Mesh out;
  out.set_positions(encode(mesh.positions));
  out.set_indices(encode(mesh.indices));
  out.set_normals(encode(mesh.normals));
  out.set_uvs(encode(mesh.uvs));
  return out;
}

v1::Scene to_proto(const Scene& scene) {
  v1::Scene out;
  for (const Mesh& mesh : scene.meshes) *out.add_meshes() = to_proto(mesh);
  for (const Instance& instance : scene.instances) {
    v1::Instance* in = out.add_instances();
    in->set_mesh(instance.mesh);
    *in->mutable_transform() = to_proto(instance.transform);
    in->set_casts_shadows(instance.casts_shadows);
    in->set_receives_shadows(instance.receives_shadows);
    if (instance.receiver_class != Instance::kNoClass)
      in->set_receiver_class(instance.receiver_class);
  }
  return out;
}

v1::Camera to_proto(const Camera& camera) {
  v1::Camera out;
  *out.mutable_eye() = to_proto(camera.eye);
  *out.mutable_target() = to_proto(camera.target);
  *out.mutable_up() = to_proto(camera.up);
  out.set_fov_deg(camera.fov_deg);
  out.set_width(camera.width);
  out.set_height(camera.height);
  out.set_near(camera.near);
  out.set_far(camera.far);
  return out;
}

v1::Light to_proto(const Light& light) {
  v1::Light out;
  out.set_size(light.size);
  switch (light.type) {
    case LightType::kDirectional:
      *out.mutable_directional()->mutable_direction() = to_proto(light.direction);
      break;
    case LightType::kSpot:
      *out.mutable_spot()->mutable_position() = to_proto(light.position);
      *out.mutable_spot()->mutable_direction() = to_proto(light.direction);
      out.mutable_spot()->set_cone_angle_deg(light.cone_angle_deg);
      break;
    case LightType::kPoint:
      *out.mutable_point()->mutable_position() = to_proto(light.position);
      break;
  }
  return out;
}

v1::ShadowMapSettings to_proto(const ShadowMapSettings& settings) {
  v1::ShadowMapSettings out;
  out.set_size(settings.size);
  out.set_technique(to_proto(settings.technique));
  if (settings.technique == Technique::kPsm || settings.technique == Technique::kPsmCube) {
    out.set_psm_casters(names::kPsmCasters.to_proto(settings.psm.casters));
    out.set_psm_near(names::kPsmNear.to_proto(settings.psm.near));
    if (settings.psm.near == PsmNear::kVirtualSlideBack)
      out.set_psm_virtual_slide(settings.psm.virtual_slide);
  }
  if (settings.technique == Technique::kLispsm && settings.lispsm.n != 0)
    out.set_lispsm_n(settings.lispsm.n);
  if (settings.technique == Technique::kVirtual) {
    out.set_virtual_lod_bias(settings.virtual_lod_bias);
    out.set_virtual_pool_pages(settings.virtual_pool_pages);
    out.set_virtual_refuse_coarsening(settings.virtual_refuse_coarsening);
  }
  out.set_fit(names::kMapFits.to_proto(settings.fit));
  if (settings.bias_world_constant != 0) out.set_bias_world_constant(settings.bias_world_constant);
  if (settings.bias_world_texel != 0) out.set_bias_world_texel(settings.bias_world_texel);
  out.set_bias_constant(settings.bias_constant);
  out.set_bias_slope(settings.bias_slope);
  return out;
}

v1::RenderRequest to_proto(const RenderRequest& request) {
  v1::RenderRequest out;
  if (request.scene) *out.mutable_scene() = to_proto(*request.scene);
  *out.mutable_camera() = to_proto(request.camera);
  for (const Light& light : request.lights) *out.add_lights() = to_proto(light);
  *out.mutable_shadow_map() = to_proto(request.shadow_map);
  for (Product product : request.products) out.add_products(to_proto(product));
  *out.mutable_filter() = to_proto(request.filter);
  if (request.atlas.tile != 0) out.mutable_atlas()->set_tile_size(request.atlas.tile);
  if (request.atlas.texel_world_size != 0)
    out.mutable_atlas()->set_texel_world_size(request.atlas.texel_world_size);
  out.mutable_atlas()->set_gutter(request.atlas.gutter);
  out.mutable_atlas()->set_generate_uvs(request.atlas.generate_uvs);
  if (request.output_format != PixelFormat::kFloat32)
    out.set_pixel_format(names::kPixelFormats.to_proto(request.output_format));
  if (request.quality.goal != Quality::Goal::kNone) {
    out.mutable_shadow_map()->clear_size();  // the goal picks it
    if (request.quality.goal == Quality::Goal::kMaxError)
      out.mutable_quality()->set_max_error(float(request.quality.value));
    else
      out.mutable_quality()->set_max_device_ms(float(request.quality.value));
  }
  return out;
}

}  // namespace shadow::convert
