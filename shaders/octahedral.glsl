// Octahedral unit-vector encoding, 2 x snorm16 (Cigolle et al. 2014, "A Survey of Efficient Representations
// for Independent Unit Vectors"); the C++ side is octEncode / octDecode in engine/scene/mesh_build.cpp.
#ifndef VISBUF_OCTAHEDRAL_GLSL
#define VISBUF_OCTAHEDRAL_GLSL

vec3 octDecode(uint packed) {
  vec2 f = unpackSnorm2x16(packed);
  vec3 n = vec3(f, 1.0 - abs(f.x) - abs(f.y));
  float t = max(-n.z, 0.0);
  n.x += n.x >= 0.0 ? -t : t;
  n.y += n.y >= 0.0 ? -t : t;
  return normalize(n);
}

uint octEncode(vec3 n) {
  float l1 = abs(n.x) + abs(n.y) + abs(n.z);
  if (!(l1 > 0.0)) return packSnorm2x16(vec2(0.0));  // (0,0) decodes to +Z
  vec2 p = n.xy / l1;
  if (n.z < 0.0) p = (1.0 - abs(p.yx)) * vec2(p.x >= 0.0 ? 1.0 : -1.0, p.y >= 0.0 ? 1.0 : -1.0);
  return packSnorm2x16(p);
}

#endif
