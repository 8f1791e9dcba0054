// edge_sampling_partials: per camera row, the pixels seen (not NaN) in `difference`, |hard -
// filtered| of two tests of the same map (pcf.cl, PCF_EDGE), and its sum over them. With the
// hard test and the bilinear 2x2 filter, the mean is the misclassified share edge sampling alone
// explains (a shadow edge lies anywhere between two texel centres): TECHNIQUE_AUTO's trial of its
// candidates (engine/passes/edge_sampling.hpp). The host sums the rows.
kernel void edge_sampling_partials(global const float* difference, uint width, uint height,
                                   global float2* partials) {
  uint y = get_global_id(0);
  if (y >= height) return;
  global const float* d = difference + (size_t)y * width;
  float seen = 0.0f, sum = 0.0f;
  for (uint x = 0; x < width; ++x) {
    bool is_seen = !isnan(d[x]);
    seen += is_seen ? 1.0f : 0.0f;
    sum += is_seen ? d[x] : 0.0f;
  }
  partials[y] = (float2)(seen, sum);
}
