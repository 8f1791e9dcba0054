// Perspective aliasing per camera pixel: the size in pixels of one shadow-map texel's footprint
// on the visible surface (> 1: the map under-samples there). NaN where the camera sees nothing
// or the point lies outside the map. A cube (-DCUBE_FACES) is one launch: each pixel reads the
// matrix of its face, and a face not rendered has a zero matrix (outside: NaN).
//
// On the surface's tangent plane, J_light maps a tangent step to map texels and J_camera to
// image pixels (both the exact derivative of a projective map, as in the shadow test's slope
// bias). A = J_camera * inverse(J_light) maps a texel step to pixels; its larger singular value
// is the length of the texel's longest footprint axis in pixels.

#define PIXEL_CHUNK 64

// d(ndc.xy) / dt for tangent t at point c = M * (p, 1), scaled to texels or pixels.
inline float2 ndc_step(float16 m, float4 c, float3 t, float2 scale) {
  float4 mt = mul_m4(m, (float4)(t, 0.0f));
  return (mt.xy - (c.xy / c.w) * mt.w) / c.w * scale;
}

kernel void texel_density(global const float* position, global const float4* normal,
                          uint pixel_count, float16 single_to_ndc, faces_t faces, cube_ndc_t cube,
                          uint map_size, float16 camera_to_ndc, uint width, uint height,
                          global float* density) {
  uint first = get_global_id(0) * PIXEL_CHUNK;
  uint last = min(first + PIXEL_CHUNK, pixel_count);
  float2 texels = (float2)((float)map_size, (float)map_size);
  float2 pixels = (float2)((float)width, (float)height);
  for (uint p = first; p < last; ++p) {
    float3 x = vload3(p, position);
#ifdef CUBE_FACES
    float16 light_to_ndc = cube.to_ndc[cube_face(&faces, x.x, x.y, x.z)];
#else
    float16 light_to_ndc = single_to_ndc;
#endif
    float out = NAN;
    float4 cl = mul_m4(light_to_ndc, (float4)(x, 1.0f));
    float2 s = cl.xy / cl.w;
    if (!isnan(x.x) && cl.w > 0.0f && s.x >= 0.0f && s.y >= 0.0f && s.x < 1.0f && s.y < 1.0f) {
      float3 n = normal[p].xyz;
      float3 t1 =
          normalize(fabs(n.x) < 0.9f ? cross(n, (float3)(1, 0, 0)) : cross(n, (float3)(0, 1, 0)));
      float3 t2 = cross(n, t1);
      float4 cc = mul_m4(camera_to_ndc, (float4)(x, 1.0f));
      float2 l1 = ndc_step(light_to_ndc, cl, t1, texels),
             l2 = ndc_step(light_to_ndc, cl, t2, texels);
      float2 c1 = ndc_step(camera_to_ndc, cc, t1, pixels),
             c2 = ndc_step(camera_to_ndc, cc, t2, pixels);
      float det = l1.x * l2.y - l2.x * l1.y;
      if (det == 0.0f) {
        out = INFINITY;  // the light grazes the surface: one texel covers a whole line
      } else {
        // inverse(J_light) = [l2.y, -l2.x; -l1.y, l1.x] / det; A = J_camera * that.
        float2 a1 = (c1 * l2.y - c2 * l1.y) / det, a2 = (c2 * l1.x - c1 * l2.x) / det;
        // Largest singular value of [a1 a2] without the cancellation of the eigenvalue form.
        out = 0.5f * (hypot(a1.x + a2.y, a1.y - a2.x) + hypot(a1.x - a2.y, a1.y + a2.x));
      }
    }
    density[p] = out;
  }
}
