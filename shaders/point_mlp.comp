#version 450
#extension GL_EXT_control_flow_attributes : require
#extension GL_GOOGLE_include_directive : require
// One PointNet++ MLP layer (see point_mlp.glsl), reading the activations / the
// cloud through uniform texel buffers: on lavapipe a texel fetch is a gather, a
// storage-buffer load with per-invocation addresses a loop over the lanes.
layout(binding = 0) uniform samplerBuffer A;   // R32F
layout(binding = 1) uniform samplerBuffer A4;  // binding 0 again, RGBA32F
layout(binding = 8) uniform samplerBuffer F;   // R32F
layout(binding = 9) uniform samplerBuffer F4;  // binding 8 again, RGBA32F
#define LOAD_A(i) texelFetch(A, int(i)).x
#define LOAD_A4(i) texelFetch(A4, int(i))
#define LOAD_F(i) texelFetch(F, int(i)).x
#define LOAD_F4(i) texelFetch(F4, int(i))
#include "point_mlp.glsl"
