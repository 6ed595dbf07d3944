#version 450
#extension GL_EXT_control_flow_attributes : require
#extension GL_GOOGLE_include_directive : require
// One PointNet++ MLP layer (see point_mlp.glsl): activations, cloud, centres and
// indices through uniform texel buffers, the weights from a storage buffer.
#include "point_mlp_texel.glsl"
#include "point_mlp.glsl"
