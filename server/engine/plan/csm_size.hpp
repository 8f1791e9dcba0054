// The CSM basis' device bytes (engine/passes/csm.hpp), for validation, admission and the pass.
// Pure host code.
#pragma once

#include <cstdint>

#include "engine/plan/plan.hpp"

namespace shadow {

// Bytes of the whole basis (every family present) with its prefilter.
uint64_t csm_basis_bytes(uint32_t size, uint32_t terms, bool half, bool blocker,
                         CsmPrefilter prefilter);
// Bytes of one family of `channels` basis channels, with its mips when lookups read mips.
uint64_t csm_basis_family_bytes(uint32_t size, uint32_t channels, bool half,
                                CsmPrefilter prefilter);
// Bytes of its largest buffer (one family of M channels, or its SAT).
uint64_t csm_family_bytes(uint32_t size, uint32_t terms, bool half, CsmPrefilter prefilter);

}  // namespace shadow
