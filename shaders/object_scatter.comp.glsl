#version 460
// Object-record upload (passes/object_upload_pass.h): thread i copies staged record i (ObjectData, 64 bytes) to
// its object ID's place in the object buffer. One dispatch per frame with changes, however scattered the IDs
// (a copy command would need one region per run of consecutive IDs).
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

layout(local_size_x = 64) in;

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Records { uvec4 records[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer Ids { uint ids[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer Objects { uvec4 objects[]; };

layout(push_constant) uniform Push {
  uvec2 records;  // staging: `count` records, then `count` object IDs
  uvec2 ids;
  uvec2 objects;  // the scene's object buffer
  uint count;
} pc;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= pc.count) return;
  const uint id = Ids(pc.ids).ids[i];
  Records src = Records(pc.records);
  Objects dst = Objects(pc.objects);
  for (uint k = 0; k < 4; ++k) dst.objects[id * 4 + k] = src.records[i * 4 + k];
}
