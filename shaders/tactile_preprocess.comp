#version 450
#extension GL_EXT_control_flow_attributes : require
#extension GL_GOOGLE_include_directive : require
// Tactile preprocessing (see tactile_preprocess.glsl), the image as a texel buffer.
layout(binding = 0) uniform isamplerBuffer Img;  // R32I
#define LOAD_IMG(i) texelFetch(Img, int(i)).x
#include "tactile_preprocess.glsl"
