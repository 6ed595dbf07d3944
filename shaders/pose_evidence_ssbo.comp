#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// pose_evidence.glsl with its tables in storage buffers (past the device's texel-buffer limit).
layout(std430, binding = 0) readonly buffer Samples_ { vec4 smp4[]; };  // [S, 12]: point, 0, normal, 0, t1, 0
layout(std430, binding = 1) readonly buffer Dense_ { vec4 dense4[]; };  // [D, 8]: point, sample, normal, 0
layout(std430, binding = 2) readonly buffer Cells_ { ivec2 cells[]; };  // [V, 2]
layout(std430, binding = 3) readonly buffer Spins_ { vec2 spins[]; };   // [NS, 2] cos, sin
layout(std430, binding = 5) readonly buffer Fields_ { float fields[]; }; // [F, H]
#define LOAD_SMP(i) smp4[i]
#define LOAD_DENSE(i) dense4[i]
#define LOAD_CELL(c) cells[c]
#define LOAD_SPIN(j) spins[j]
#define LOAD_FIELD(i) fields[i]
#include "pose_evidence.glsl"
