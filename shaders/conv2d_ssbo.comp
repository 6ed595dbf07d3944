#version 450
#extension GL_EXT_control_flow_attributes : require
#extension GL_GOOGLE_include_directive : require
// conv2d reading storage buffers: the fallback when a tensor exceeds the
// device's maxTexelBufferElements (see conv2d.comp).
layout(std430, binding = 0) readonly buffer X_ { float X[]; };
layout(std430, binding = 1) readonly buffer W_ { float Wt[]; };
layout(std430, binding = 2) readonly buffer W4_ { vec4 Wt4[]; };  // binding 1 seen as vec4
layout(std430, binding = 3) readonly buffer B_ { float Bias[]; };
layout(std430, binding = 4) readonly buffer Res_ { float Res[]; };
#define LOAD_X(i) X[i]
#define LOAD_W(i) Wt[i]
#define LOAD_W4(i) Wt4[i]
#define LOAD_BIAS(i) Bias[i]
#define LOAD_RES(i) Res[i]
// Bindings 6 and 8 (x and the residual as vec4) are bound but unused: XVEC4 and
// YVEC4 stay false here.
#include "conv2d.glsl"
