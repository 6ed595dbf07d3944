#version 450
#extension GL_EXT_control_flow_attributes : require
#extension GL_GOOGLE_include_directive : require
// One PointNet++ MLP layer (see point_mlp.glsl), storage-buffer reads.
layout(std430, binding = 0) readonly buffer A_ { float A[]; };
layout(std430, binding = 1) readonly buffer A4_ { vec4 A4[]; };  // binding 0 as vec4
layout(std430, binding = 6) readonly buffer C_ { float centre[]; };  // MODE 1: [S][3]
layout(std430, binding = 7) readonly buffer I_ { int idx[]; };       // MODE 1 (and PAD): [S][NS]
layout(std430, binding = 8) readonly buffer F_ { float feat[]; };
layout(std430, binding = 9) readonly buffer F4_ { vec4 feat4[]; };
layout(std430, binding = 10) readonly buffer H4_ { vec4 h4[]; };   // HIDDEN: W0 [CF + 3][K]
layout(std430, binding = 11) readonly buffer HB4_ { vec4 hb4[]; };  // HIDDEN: b0 [K]
#define LOAD_A(i) A[i]
#define LOAD_A4(i) A4[i]
#define LOAD_C(i) centre[i]
#define LOAD_I(i) idx[i]
#define LOAD_F(i) feat[i]
#define LOAD_F4(i) feat4[i]
#define LOAD_H4(i) h4[i]
#define LOAD_HB4(i) hb4[i]
#include "point_mlp.glsl"
