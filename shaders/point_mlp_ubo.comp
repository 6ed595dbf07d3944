#version 450
#extension GL_EXT_control_flow_attributes : require
#extension GL_GOOGLE_include_directive : require
// point_mlp.comp with the weights in a uniform buffer (binding 3): every lane
// reads a weight at the same address, which a CPU driver turns into one load
// and a broadcast; from a storage buffer it is a loop over the lanes, which was
// most of the layer's time on an AVX2-only CPU (README "On CPUs without AVX-512, measured").
layout(binding = 0) uniform samplerBuffer A;   // R32F
layout(binding = 1) uniform samplerBuffer A4;  // binding 0 again, RGBA32F
layout(binding = 8) uniform samplerBuffer F;   // R32F
layout(binding = 9) uniform samplerBuffer F4;  // binding 8 again, RGBA32F
#define LOAD_A(i) texelFetch(A, int(i)).x
#define LOAD_A4(i) texelFetch(A4, int(i))
#define LOAD_F(i) texelFetch(F, int(i)).x
#define LOAD_F4(i) texelFetch(F4, int(i))
#define WEIGHTS_UNIFORM
#include "point_mlp.glsl"
