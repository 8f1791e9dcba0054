#include "engine/passes/csm.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "engine/passes/light_args.hpp"
#include "engine/passes/pixel_shape.hpp"
#include "engine/plan/filter.hpp"

namespace shadow {
namespace {
constexpr uint32_t kTexelChunk = 256;  // CSM_TEXEL_CHUNK in csm.cl
constexpr uint32_t kPixelChunk = 64;   // CSM_PIXEL_CHUNK
constexpr int kModeFixed = 0, kModePcss = 1;

}  // namespace

CsmDepthItem csm_depth_mapping(const MapDepth& depth) {
  CsmDepthItem m{};
  m.inv_range = 1.0f;  // kStored: z as it is
  if (depth.kind == MapDepth::kStored) return m;
  const double n = depth.near, f = depth.far;
  m.d_near = float(n);
  m.inv_range = float(1.0 / (f - n));
  if (depth.kind == MapDepth::kPerspective) {  // z(n) = 0, z(f) = 1
    m.perspective = 1;
    m.alpha = float(f / (f - n));
    m.beta = float(-f * n / (f - n));
  }
  return m;
}

std::string csm_depth_mapping_text(const MapDepth& depth) {
  char buf[320];
  switch (depth.kind) {
    case MapDepth::kPerspective:
      std::snprintf(buf, sizeof buf,
                    "linear: z = (d - %.9g) / %.9g, d = distance along the map's axis (the "
                    "light's, or PSM's post-perspective light's), where NDC z = %.9g - %.9g / d",
                    depth.near, depth.far - depth.near, depth.far / (depth.far - depth.near),
                    depth.far * depth.near / (depth.far - depth.near));
      break;
    case MapDepth::kOrthographic:
      std::snprintf(buf, sizeof buf,
                    "linear: z = NDC z (orthographic) = (d - %.9g) / %.9g, d = distance along the "
                    "light's direction",
                    depth.near, depth.far - depth.near);
      break;
    case MapDepth::kStored:
      std::snprintf(buf, sizeof buf,
                    "stored: z = the map's NDC z, monotone with the distance from the light but "
                    "not linear in it (a warped map: PSM or LiSPSM)");
      break;
  }
  return buf;
}

CsmControlsItem csm_controls(const CsmSettings& s) {
  // The series' transition narrows as 1/M, so the offset is given in units of 1/M.
  return {s.damping, s.depth_offset / float(s.terms), s.scale, CsmPass::kMinOccluded};
}

std::vector<std::string> csm_channel_names(uint32_t terms, bool blocker) {
  std::vector<std::string> names;
  for (const char* family : {"sin", "cos", "zsin", "zcos"}) {
    if (!blocker && family[0] == 'z') break;
    for (uint32_t k = 1; k <= terms; ++k) names.push_back(family + std::to_string(k));
  }
  if (blocker) names.push_back("z");
  return names;
}

std::string CsmPass::options(bool half, bool sat, bool cube_face) const {
  std::string o;
  for (const auto& [on, define] :
       {std::pair{half, "-DCSM_HALF"}, {sat, "-DCSM_SAT"}, {cube_face, "-DCUBE_FACES"}})
    if (on) {
      if (!o.empty()) o += ' ';
      o += define;
    }
  return pixel_shape(runtime_, kPixelChunk).with(o);  // the same options for either strip
}

cl::Events CsmPass::launch_texels(cl_kernel kernel, size_t count) const {
  const PixelShape shape = pixel_shape(runtime_, kTexelChunk);
  return runtime_.launch(kernel, shape.work_items(uint32_t(count)), shape.group);
}

cl::Events CsmPass::launch_pixels(cl_kernel kernel, size_t count) const {
  const PixelShape shape = pixel_shape(runtime_, kPixelChunk);
  return runtime_.launch(kernel, shape.work_items(uint32_t(count)), shape.group);
}

void CsmPass::warm_up() {
  mips_.warm_up();
  sats_.warm_up();
  for (bool half : {false, true}) {
    for (const char* k : {"csm_basis", "csm_pack"}) kernels_.kernel("csm.cl", k, options(half));
    // The lookups: from mips (float32 or float16) or SATs (float32 storage only).
    for (bool sat : {false, true}) {
      if (half && sat) continue;
      kernels_.kernel("csm.cl", "csm_probe", options(half, sat));
      for (bool cube : {false, true})
        kernels_.kernel("csm.cl", "csm_visibility", options(half, sat, cube));
    }
  }
}

const CsmBasis& CsmPass::build(const cl::Buffer& map, uint32_t size, const MapDepth& depth,
                               uint32_t terms, bool half, bool blocker, CsmPrefilter prefilter,
                               Timeline& timeline) {
  // The last build's dims and offsets writes may still be reading dims_host and offsets_host,
  // which this one rewrites (a cube builds a basis per face, sizes differing for the faces not
  // rendered): let them finish first.
  runtime_.finish();
  CsmBasis& b = basis_;
  const CsmDepthItem mapping = csm_depth_mapping(depth);
  b.size = size;
  b.terms = terms;
  b.half = half;
  b.blocker = blocker;
  b.prefilter = prefilter;
  b.depth = depth;
  b.mapping = mapping;
  for (int f = 0; f < kCsmFamilies; ++f) {
    const bool present = f < kCsmZSin || blocker;
    const uint32_t channels = f == kCsmZ ? 1 : terms;
    runtime_.ensure(b.families[f], present ? csm_basis_family_bytes(size, channels, half, prefilter)
                                           : (half ? 2 : 4));
    b.tables[f] = &b.families[f];
  }
  const size_t texels = size_t{size} * size;
  cl_kernel k = kernels_.kernel("csm.cl", "csm_basis", options(half));
  cl::set_args(k, map, uint32_t(texels), mapping, terms, int(blocker), b.families[kCsmSin],
               b.families[kCsmCos], b.families[kCsmZSin], b.families[kCsmZCos], b.families[kCsmZ]);
  timeline.add("csm.basis", launch_texels(k, texels));

  b.dims_host.assign(1, glm::uvec2(size, size));
  b.offsets_host.assign(1, 0);
  static constexpr const char* kSatPasses[kCsmFamilies] = {
      "csm.sat.sin", "csm.sat.cos", "csm.sat.zsin", "csm.sat.zcos", "csm.sat.z"};
  if (prefilter == CsmPrefilter::kSat)  // float32 storage: the SAT pass reads floats
    for (int f = 0; f < kCsmFamilies; ++f)
      if (f < kCsmZSin || blocker)
        b.tables[f] =
            &sats_
                 .run({&b.families[f], size, size, f == kCsmZ ? 1 : terms}, kSatPasses[f], timeline)
                 .sums;
  if (prefilter == CsmPrefilter::kMips) {
    for (const MipLevel& l : mip_levels(size, size)) {
      b.dims_host.emplace_back(l.width, l.height);
      b.offsets_host.push_back(texels + l.offset);
    }
    for (int f = 0; f < kCsmFamilies; ++f)
      if (f < kCsmZSin || blocker)
        mips_.run_in_place(b.families[f], size, size, f == kCsmZ ? 1 : terms, half, "csm.mips",
                           timeline);
  }
  b.levels = uint32_t(b.dims_host.size());
  runtime_.ensure(b.dims, b.dims_host.size() * sizeof(glm::uvec2));
  runtime_.ensure(b.offsets, b.offsets_host.size() * sizeof(uint64_t));
  timeline.add("csm.basis",
               runtime_.write(b.dims, b.dims_host.data(), b.dims_host.size() * sizeof(glm::uvec2)));
  timeline.add("csm.basis", runtime_.write(b.offsets, b.offsets_host.data(),
                                           b.offsets_host.size() * sizeof(uint64_t)));
  return b;
}

const cl::Buffer& CsmPass::visibility(const GBuffer& gb, uint32_t pixels, const CsmBasis& b,
                                      const ViewSetup& light_view, const Light& light,
                                      const ShadowMapSettings& settings, const Filter& filter,
                                      bool want_blocker, Timeline& timeline) {
  runtime_.ensure(visibility_, size_t{pixels} * sizeof(float));
  runtime_.ensure(blocker_, want_blocker ? size_t{pixels} * sizeof(float) : sizeof(float));
  const PcssGeometry geo = pcss_geometry(light_view, light, settings.size);
  const bool pcss = filter_facts(filter.kind).csm_blocker;
  const std::string pass = pcss ? "visibility.pcss_csm" : "visibility.csm";
  cl_kernel k = kernels_.kernel("csm.cl", "csm_visibility", lookup_options(b, &light_view));
  cl::set_args(k, gb.position, gb.normal, pixels, shadow_lookup(light_view, light, settings),
               faces_args(light_view.faces), b.mapping, *b.tables[kCsmSin], *b.tables[kCsmCos],
               *b.tables[kCsmZSin], *b.tables[kCsmZCos], *b.tables[kCsmZ], b.terms, b.dims,
               b.offsets, b.levels, csm_controls(filter.csm), pcss ? kModePcss : kModeFixed,
               filter.csm.window, geo.size, geo.scale, int(want_blocker), visibility_, blocker_);
  timeline.add(pass, launch_pixels(k, pixels));
  return visibility_;
}

const cl::Buffer& CsmPass::pack(const CsmBasis& b, Timeline& timeline) {
  const size_t texels = size_t{b.size} * b.size;
  runtime_.ensure(packed_, texels * b.channels() * sizeof(float));
  cl_kernel k = kernels_.kernel("csm.cl", "csm_pack", options(b.half));
  cl::set_args(k, b.families[kCsmSin], b.families[kCsmCos], b.families[kCsmZSin],
               b.families[kCsmZCos], b.families[kCsmZ], uint32_t(texels), b.terms, int(b.blocker),
               packed_);
  timeline.add("csm.pack", launch_texels(k, texels));
  return packed_;
}

std::vector<glm::vec4> CsmPass::probe(const CsmBasis& b, const std::vector<glm::vec4>& points,
                                      const CsmControlsItem& controls, Timeline& timeline) {
  const uint32_t n = uint32_t(points.size());
  std::vector<glm::vec4> out(n);
  if (n == 0) return out;
  runtime_.ensure(points_, n * sizeof(glm::vec4));
  runtime_.ensure(probed_, n * sizeof(glm::vec4));
  timeline.add("csm.probe", runtime_.write(points_, points.data(), n * sizeof(glm::vec4)));
  cl_kernel k = kernels_.kernel("csm.cl", "csm_probe", lookup_options(b));
  cl::set_args(k, points_, n, *b.tables[kCsmSin], *b.tables[kCsmCos], *b.tables[kCsmZSin],
               *b.tables[kCsmZCos], *b.tables[kCsmZ], b.terms, b.dims, b.offsets, b.levels,
               controls, int(b.blocker), probed_);
  timeline.add("csm.probe", launch_pixels(k, n));
  runtime_.read(probed_, out.data(), n * sizeof(glm::vec4));
  return out;
}

}  // namespace shadow
