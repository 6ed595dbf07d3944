#version 450
// The indentation's gradient per pixel (engine/ops/gel_shape.cpp; CPU mirror engine/ops/gel_ops.h):
// the four nearest tiles' tables at the colour change's cell, blended by the pixel's place
// between the tile centres, less the same for no colour change; where that slope is gentle, the
// pixel's linearised inverse of the shading instead.
layout(local_size_x_id = 0) in;
layout(std430, binding = 0) readonly buffer Frame_ { float frame[]; };  // [H, W, 3]
layout(std430, binding = 1) readonly buffer Empty_ { float empty[]; };  // [H, W, 3]
layout(std430, binding = 2) readonly buffer Lut_ { float lut[]; };      // [ty * tx, n^3, 2]
layout(std430, binding = 3) readonly buffer Linear_ { float linear[]; };  // [H, W, 6]
layout(std430, binding = 4) writeonly buffer Out_ { float outv[]; };    // [H, W, 2]
layout(push_constant) uniform Push { int H; int W; int n; int ty; int tx; float gentle; } p;

int cell_of(float v) {
    precise float q = floor((v + 256.0) * float(p.n) / 512.0);
    return int(clamp(q, 0.0, float(p.n - 1)));
}

vec2 table_gradient(int r, int c, vec3 d) {
    const uint cell = (uint(cell_of(d.x)) * uint(p.n) + uint(cell_of(d.y))) * uint(p.n) + uint(cell_of(d.z));
    precise float fy = clamp((float(r) + 0.5) * float(p.ty) / float(p.H) - 0.5, 0.0, float(p.ty - 1));
    precise float fx = clamp((float(c) + 0.5) * float(p.tx) / float(p.W) - 0.5, 0.0, float(p.tx - 1));
    const int a0 = p.ty > 1 ? min(int(fy), p.ty - 2) : 0, b0 = p.tx > 1 ? min(int(fx), p.tx - 2) : 0;
    precise float wy = fy - float(a0), wx = fx - float(b0);
    const uint n3 = uint(p.n) * uint(p.n) * uint(p.n);
    precise vec2 g = vec2(0.0);
    for (int da = 0; da < 2; ++da)
        for (int db = 0; db < 2; ++db) {
            precise float w = (da == 1 ? wy : 1.0 - wy) * (db == 1 ? wx : 1.0 - wx);
            const int a = min(a0 + da, p.ty - 1), b = min(b0 + db, p.tx - 1);
            const uint base = ((uint(a) * uint(p.tx) + uint(b)) * n3 + cell) * 2u;
            g += w * vec2(lut[base], lut[base + 1u]);
        }
    return g;
}

void main() {
    const uint HW = uint(p.H) * uint(p.W), stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint q = gl_GlobalInvocationID.x; q < HW; q += stride) {
        const int r = int(q / uint(p.W)), c = int(q % uint(p.W));
        const vec3 d = vec3(frame[3u * q] - empty[3u * q], frame[3u * q + 1u] - empty[3u * q + 1u], frame[3u * q + 2u] - empty[3u * q + 2u]);
        precise vec2 g = table_gradient(r, c, d) - table_gradient(r, c, vec3(0.0));
        precise float m2 = g.x * g.x + g.y * g.y;
        if (p.gentle > 0.0 && m2 <= p.gentle * p.gentle) {
            const uint b = 6u * q;
            precise float lr = (linear[b] * d.x + linear[b + 1u] * d.y) + linear[b + 2u] * d.z;
            precise float lc = (linear[b + 3u] * d.x + linear[b + 4u] * d.y) + linear[b + 5u] * d.z;
            g = vec2(lr, lc);
        }
        outv[2u * q] = g.x;
        outv[2u * q + 1u] = g.y;
    }
}
