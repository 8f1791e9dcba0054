// Convolution shadow maps (kernels/csm.cl, Annen et al. 2007/2008, seed 004 §2.2): the Fourier
// basis of a map's linear depth, its mips, and the lookups on them: the prefiltered shadow test
// (FILTER_CSM), the blocker average and PCSS-CSM soft shadows (FILTER_PCSS_CSM).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "engine/device_types.hpp"
#include "engine/passes/gbuffer.hpp"
#include "engine/passes/mip_pyramid.hpp"
#include "engine/passes/pcss.hpp"
#include "engine/passes/summed_area.hpp"
#include "engine/plan/csm_size.hpp"
#include "engine/plan/plan.hpp"

namespace shadow {

// The basis' channel families, one buffer each, [texel][M] interleaved (z: one channel), level 0
// then its mips: a family of M = 16 float32 channels stays under the 2 GiB per buffer up to
// 4096^2 (1.43 GB with mips), where sin and cos together would not (2.1 GB without). With the
// SAT lookup each family has a float64 summed-area table beside it (up to 2048^2 at M = 16).
enum CsmFamily { kCsmSin, kCsmCos, kCsmZSin, kCsmZCos, kCsmZ, kCsmFamilies };

struct CsmBasis {
  uint32_t size = 0;     // the map's texels per side
  uint32_t terms = 0;    // M
  bool half = false;     // half-float storage
  bool blocker = false;  // the z-weighted families and z are present
  uint32_t levels = 1;   // level 0 and the mip levels after it
  CsmPrefilter prefilter = CsmPrefilter::kNone;
  MapDepth depth;          // the map's
  CsmDepthItem mapping{};  // and the kernels' form of it
  std::array<cl::Buffer, kCsmFamilies> families;
  std::array<const cl::Buffer*, kCsmFamilies> tables{};  // what lookups read: families or SATs
  cl::Buffer dims, offsets;                              // per level: (w, h) and its first texel
  std::vector<glm::uvec2> dims_host;  // the writes' sources (they are asynchronous)
  std::vector<uint64_t> offsets_host;

  uint32_t channels() const { return blocker ? 4 * terms + 1 : 2 * terms; }
};

// The linear [0, 1] depth of a map (csm.cl): orthographic z_ndc as it is, perspective
// (d - near) / (far - near) of the distance d along the map's axis (z_ndc = alpha + beta / d),
// and a warped map's z_ndc as stored.
CsmDepthItem csm_depth_mapping(const MapDepth& depth);
// The same in words, for the texture's metadata.
std::string csm_depth_mapping_text(const MapDepth& depth);
// The kernels' controls from the request's settings.
CsmControlsItem csm_controls(const CsmSettings& s);
// Channel names of the packed basis: sin1..sinM, cos1..cosM[, zsin1.., zcos1.., z].
std::vector<std::string> csm_channel_names(uint32_t terms, bool blocker);

class CsmPass {
 public:
  static constexpr uint32_t kMaxTerms = 16;  // CSM_MAX_TERMS in csm.cl
  // Below this occluded fraction a window has no blocker (lit in PCSS-CSM, as PCSS's zero
  // blockers): above the ringing of a lit window at the default controls.
  static constexpr float kMinOccluded = 0.05f;

  CsmPass(const cl::Runtime& runtime, cl::Kernels& kernels, MipPyramidPass& mips,
          SummedAreaPass& sats)
      : runtime_(runtime), kernels_(kernels), mips_(mips), sats_(sats) {}

  // The basis of `map` (size^2 NDC depths); with `blocker` the z-weighted families too,
  // prefiltered as the lookups will read it (mips or SATs). Valid until the next build.
  const CsmBasis& build(const cl::Buffer& map, uint32_t size, const MapDepth& depth, uint32_t terms,
                        bool half, bool blocker, CsmPrefilter prefilter, Timeline& timeline);
  // Visibility per camera pixel (FILTER_CSM or FILTER_PCSS_CSM, 1 lit, NaN where nothing is
  // seen), and with `want_blocker` the blocker average in blocker(). Valid until the next run.
  const cl::Buffer& visibility(const GBuffer& gbuffer, uint32_t pixels, const CsmBasis& basis,
                               const ViewSetup& light_view, const Light& light,
                               const ShadowMapSettings& settings, const Filter& filter,
                               bool want_blocker, Timeline& timeline);
  const cl::Buffer& blocker() const { return blocker_; }
  const CsmBasis& basis() const { return basis_; }  // the last build's
  // The basis as one float texture, channels as csm_channel_names (level 0 only).
  const cl::Buffer& pack(const CsmBasis& basis, Timeline& timeline);
  // Lookups at points (u, v, window in texels, d): (visibility, raw occluded fraction, blocker
  // average, its occluded fraction), the blocker fields NaN unless the basis has them.
  std::vector<glm::vec4> probe(const CsmBasis& basis, const std::vector<glm::vec4>& points,
                               const CsmControlsItem& controls, Timeline& timeline);
  void warm_up();

 private:
  // Half-float storage, lookups from SATs, and the per-pixel face check of a cube face, in the
  // device profile's shape (a strip of texels or pixels per work-item, or one).
  std::string options(bool half, bool sat = false, bool cube_face = false) const;
  // The lookups' program for this basis (and a cube face's pixel check).
  std::string lookup_options(const CsmBasis& b, const ViewSetup* map = nullptr) const {
    return options(b.half, b.prefilter == CsmPrefilter::kSat, map && map->faces.owned != 0);
  }
  // Launches `kernel` over `count` texels (strips of kTexelChunk on the CPU shape) or pixels.
  cl::Events launch_texels(cl_kernel kernel, size_t count) const;
  cl::Events launch_pixels(cl_kernel kernel, size_t count) const;
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  MipPyramidPass& mips_;
  SummedAreaPass& sats_;
  CsmBasis basis_;
  cl::Buffer visibility_, blocker_, packed_, points_, probed_;
};

}  // namespace shadow
