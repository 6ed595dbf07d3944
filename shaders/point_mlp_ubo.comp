#version 450
#extension GL_EXT_control_flow_attributes : require
#extension GL_GOOGLE_include_directive : require
// point_mlp.comp with the weights in a uniform buffer (binding 3), for devices
// without subgroup shuffles: lavapipe (Mesa 22.3) reads them by a plain gather,
// from a storage buffer by a loop over the lanes with a branch per lane, which
// was most of the layer's time on an AVX2-only CPU (docs/performance.md "On CPUs
// without AVX-512, measured").
#include "point_mlp_texel.glsl"
#define WEIGHTS_UNIFORM
#include "point_mlp.glsl"
