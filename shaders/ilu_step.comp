#version 450
#extension GL_GOOGLE_include_directive : require
// One ILU iteration per dispatch (ilu_step_main.glsl), row sums through shared memory.
#include "ilu_step_main.glsl"
