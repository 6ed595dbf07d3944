#version 450
#extension GL_EXT_control_flow_attributes : require
#extension GL_GOOGLE_include_directive : require
// Tactile preprocessing (see tactile_preprocess.glsl), the image as a storage buffer.
layout(std430, binding = 0) readonly buffer Img_ { int img[]; };
#define LOAD_IMG(i) img[i]
#include "tactile_preprocess.glsl"
