#version 450
#extension GL_GOOGLE_include_directive : require
// Farthest point sampling with a shared-memory tree reduction (see fps.glsl).
#include "fps.glsl"
