#version 450
// Does nothing: timing it gives the per-dispatch overhead of a device.
layout(local_size_x_id = 0) in;
layout(std430, binding = 0) writeonly buffer Out_ { float outv[]; };
void main() {}
