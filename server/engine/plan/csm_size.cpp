#include "engine/plan/csm_size.hpp"

#include <algorithm>

#include "engine/plan/mip_levels.hpp"

namespace shadow {
namespace {

// A family's SAT, if any.
uint64_t sat_family_bytes(uint32_t size, uint32_t channels, CsmPrefilter prefilter) {
  return prefilter == CsmPrefilter::kSat ? uint64_t{size} * size * channels * sizeof(double) : 0;
}

}  // namespace

uint64_t csm_basis_family_bytes(uint32_t size, uint32_t channels, bool half,
                                CsmPrefilter prefilter) {
  const uint64_t texels =
      prefilter == CsmPrefilter::kMips ? mip_chain_texels(size, size) : uint64_t{size} * size;
  return texels * channels * (half ? 2 : 4);
}

uint64_t csm_family_bytes(uint32_t size, uint32_t terms, bool half, CsmPrefilter prefilter) {
  return std::max(csm_basis_family_bytes(size, terms, half, prefilter),
                  sat_family_bytes(size, terms, prefilter));
}

uint64_t csm_basis_bytes(uint32_t size, uint32_t terms, bool half, bool blocker,
                         CsmPrefilter prefilter) {
  const auto family = [&](uint32_t channels) {
    return csm_basis_family_bytes(size, channels, half, prefilter) +
           sat_family_bytes(size, channels, prefilter);
  };
  return family(terms) * (blocker ? 4 : 2) + (blocker ? family(1) : 0);
}

}  // namespace shadow
