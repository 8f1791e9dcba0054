// The camera view's surface at a grid of pixels (kernels/view_samples.cl): where a
// quality goal predicts each candidate's error (engine/choose/quality_pick.hpp). Seen surface and
// its real normals, where the receivers' boxes (receiver_samples) only bound it: a box face's
// normal says nothing of which side of a tree faces the light.
#pragma once

#include <vector>

#include "engine/choose/auto_pick.hpp"  // Sample, kSampleColumns, kSampleRows
#include "engine/cl/program_cache.hpp"
#include "engine/cl/timeline.hpp"
#include "engine/passes/gbuffer.hpp"

namespace shadow {

class ViewSamplesPass {
 public:
  ViewSamplesPass(const cl::Runtime& runtime, cl::Kernels& kernels)
      : runtime_(runtime), kernels_(kernels) {}

  // The seen pixels among the kSampleColumns x kSampleRows grid's cell centres of a
  // width x height view, in row order: position and normal (facing the camera), the normal 0
  // where the pixel receives no shadows; with `cells`, each sample's grid cell (its index in row
  // order) there too. Reads the samples back, so it waits for the view.
  std::vector<Sample> run(const GBuffer& view, uint32_t width, uint32_t height, Timeline& timeline,
                          std::vector<uint32_t>* cells = nullptr);
  void warm_up() { kernels_.kernel("view_samples.cl", "view_samples"); }

 private:
  const cl::Runtime& runtime_;
  cl::Kernels& kernels_;
  cl::Buffer samples_;
};

}  // namespace shadow
