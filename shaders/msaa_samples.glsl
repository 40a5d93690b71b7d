// MSAA resolve of the visibility buffer: the shading pass's MSAA variant (shade.comp.glsl, MSAA=1) includes this
// after material.glsl and defines shadeVisible() below it. One thread per pixel reads every sample's ID:
//   - all samples carry the same ID (the interior of a triangle, or nothing at all): one shading at the pixel
//     centre, exactly as without MSAA (the mean of the standard sample locations is the centre);
//   - otherwise (an edge): each distinct ID is shaded once, at the mean of the standard locations of the samples
//     that carry it (inside the triangle: it is convex), weighted by its sample count; samples with nothing keep
//     the background the colour image was cleared to. The sum is averaged in linear space, like a hardware
//     resolve of per-sample colours, and the pixel is counted in stats[STAT_PER_SAMPLE_PIXELS].
// The derivatives stay per pixel (the texture level of detail does not change with the sample count).
#ifndef VISBUF_MSAA_SAMPLES_GLSL
#define VISBUF_MSAA_SAMPLES_GLSL

layout(set = 1, binding = SHADE_BINDING_VISIBILITY) uniform usampler2DMS visibility;
layout(set = 1, binding = SHADE_BINDING_COLOR, rgba16f) uniform image2D colorOut;  // read back: the cleared background
layout(std430, set = 0, binding = SCENE_BINDING_STATS) buffer MsaaStatsBlock { uint stats[]; };

// The lit colour of the surface with this raw ID at `at` inside pixel p (pixel units from its top-left corner).
vec3 shadeVisible(uvec2 raw, ivec2 p, vec2 at);

// Vulkan's standard sample locations (spec, "Multisampling": "Standard sample locations"), pixel units from the
// top-left corner. The renderer requires VkPhysicalDeviceLimits::standardSampleLocations.
vec2 standardSamplePosition(uint samples, uint i) {
  if (samples == 2u) return i == 0u ? vec2(0.75, 0.75) : vec2(0.25, 0.25);
  const vec2 four[4] = vec2[](vec2(0.375, 0.125), vec2(0.875, 0.375), vec2(0.125, 0.625), vec2(0.625, 0.875));
  return four[i];
}

// Resolves pixel p; true when its samples differ (the per-sample path).
bool resolvePixel(ivec2 p) {
  const uint n = uniformBranch(frame.msaaSamples);  // (uniform_branch.glsl)
  uvec2 ids[MAX_MSAA_SAMPLES];
  bool same = true;
  for (uint i = 0u; i < n; ++i) {
    ids[i] = texelFetch(visibility, p, int(i)).xy;
    same = same && ids[i] == ids[0];
  }
  if (same) {
    if (ids[0].x != VIS_NOTHING) imageStore(colorOut, p, vec4(shadeVisible(ids[0], p, vec2(0.5)), 1.0));
    return false;
  }
  const vec3 background = imageLoad(colorOut, p).rgb;
  vec3 sum = vec3(0.0);
  uint done = 0u;
  for (uint i = 0u; i < n; ++i) {
    if ((done >> i & 1u) != 0u) continue;
    uint count = 0u;
    vec2 at = vec2(0.0);
    for (uint j = i; j < n; ++j)
      if (ids[j] == ids[i]) {
        done |= 1u << j;
        ++count;
        at += standardSamplePosition(n, j);
      }
    sum += float(count) * (ids[i].x == VIS_NOTHING ? background : shadeVisible(ids[i], p, at / float(count)));
  }
  imageStore(colorOut, p, vec4(sum / float(n), 1.0));
  return true;
}

shared uint groupPerSamplePixels;

// The whole MSAA shading thread (every invocation of the workgroup must call it: it has barriers); one atomic per
// workgroup for the per-sample pixel count.
void shadeMultisampledPixel(ivec2 p) {
  if (gl_LocalInvocationIndex == 0u) groupPerSamplePixels = 0u;
  barrier();
  if (p.x < int(frame.viewport.x) && p.y < int(frame.viewport.y) && resolvePixel(p))
    atomicAdd(groupPerSamplePixels, 1u);
  barrier();
  if (gl_LocalInvocationIndex == 0u && groupPerSamplePixels > 0u)
    atomicAdd(stats[STAT_PER_SAMPLE_PIXELS], groupPerSamplePixels);
}

#endif
