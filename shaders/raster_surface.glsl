// Fragment shaders fed by forward.vert (forward reference, transparency pass, G-buffer raster): its interpolated
// outputs, and the SurfaceInputs they give with the rasteriser's screen derivatives (the shading pass builds the
// same record from analytic derivatives in shade.comp.glsl).
#ifndef VISBUF_RASTER_SURFACE_GLSL
#define VISBUF_RASTER_SURFACE_GLSL

#include "material.glsl"

layout(location = 0) in vec3 inNormal;
layout(location = 1) in vec4 inColor;
layout(location = 2) flat in uint inMaterial;
layout(location = 3) flat in uint inObject;
layout(location = 4) in vec3 inPosition;  // camera-relative world
layout(location = 5) in vec4 inUv;        // TEXCOORD_0, TEXCOORD_1
layout(location = 6) in vec4 inTangent;   // world xyz, w: bitangent sign (0: none)

SurfaceInputs rasterSurfaceInputs() {
  SurfaceInputs si;
  si.position = inPosition;
  si.normal = inNormal;
  si.tangent = inTangent;
  si.dpdx = dFdx(inPosition);
  si.dpdy = dFdy(inPosition);
  si.uv0 = inUv.xy;
  si.uv1 = inUv.zw;
  si.duv0dx = dFdx(inUv.xy);
  si.duv0dy = dFdy(inUv.xy);
  si.duv1dx = dFdx(inUv.zw);
  si.duv1dy = dFdy(inUv.zw);
  si.color = inColor;
  // Every pipeline's front face is counter-clockwise on screen (mirrored objects' lists cull the other side);
  // the glTF front face of a mirrored object is clockwise.
  si.frontFacing = gl_FrontFacing != ((objectAt(inObject).flags & OBJECT_FLAG_FLIP_WINDING) != 0u);
  return si;
}

#endif
