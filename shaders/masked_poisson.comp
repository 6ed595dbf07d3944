#version 450
// lap(z) = div(grad) inside the mask, z = 0 outside it in the image, the image's border free (a
// ghost neighbour continues the gradient): red-black SOR (engine/ops/gel_shape.cpp; CPU mirror
// engine/ops/gel_ops.h), one dispatch a stage: kClear empties the two colours' lists of the
// pixels to update, kList sets z (the start where it updates, with a start; else 0) and appends each pixel inside the mask (and pinned by a
// neighbour) to its colour's list with its divergence, then one kHalfSweep per colour and sweep,
// a lane per pixel of the colour's list. Within a colour the updates read only the other colour,
// so the result is the reference's in any lane, workgroup or list order; the dispatches'
// barriers order the colours. The stage is a specialization constant: a CPU driver runs every
// branch of a run-time switch under lane masks.
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const int kStage = 0;
layout(constant_id = 2) const bool kHasStart = false;  // else binding 4 is a stand-in, never read
layout(std430, binding = 0) readonly buffer Grad_ { vec2 grad[]; };  // [H, W, 2]
layout(std430, binding = 1) readonly buffer Mask_ { float mask[]; };  // [H, W]
layout(std430, binding = 2) buffer Z_ { float z[]; };                 // [H, W]
// Per colour: its list's length, then the lists (colour k from k * cap): pixel, divergence bits.
layout(std430, binding = 3) buffer Ws_ { uint count[2]; uvec2 list[]; };
layout(std430, binding = 4) readonly buffer Start_ { float start[]; };  // [H, W]: the first guess
layout(push_constant) uniform Push { int H; int W; int colour; uint cap; float omega; } p;

const int kClear = 0, kList = 1, kHalfSweep = 2;

float g(int r, int c, int k) { return grad[uint(r) * uint(p.W) + uint(c)][k]; }

float divergence(int r, int c) {
    precise float dr = p.H == 1 ? 0.0 : r == 0 ? g(1, c, 0) - g(0, c, 0)
                     : r == p.H - 1 ? g(r, c, 0) - g(r - 1, c, 0) : 0.5 * (g(r + 1, c, 0) - g(r - 1, c, 0));
    precise float dc = p.W == 1 ? 0.0 : c == 0 ? g(r, 1, 1) - g(r, 0, 1)
                     : c == p.W - 1 ? g(r, c, 1) - g(r, c - 1, 1) : 0.5 * (g(r, c + 1, 1) - g(r, c - 1, 1));
    precise float s = dr + dc;
    return s;
}

void main() {
    const uint HW = uint(p.H) * uint(p.W), lanes = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    if (kStage == kClear) {
        if (gl_GlobalInvocationID.x < 2u) count[gl_GlobalInvocationID.x] = 0u;
        return;
    }
    if (kStage == kList) {
        for (uint q = gl_GlobalInvocationID.x; q < HW; q += lanes) {
            z[q] = 0.0;
            const int r = int(q / uint(p.W)), c = int(q % uint(p.W));
            const int inside = int(r > 0) + int(r + 1 < p.H) + int(c > 0) + int(c + 1 < p.W);
            if (!(mask[q] > 0.5) || inside == 0) continue;  // inside == 0: a 1 x 1 image, nothing pins it
            if (kHasStart) z[q] = start[q];
            const uint colour = uint((r + c) & 1), k = atomicAdd(count[colour], 1u);
            list[colour * p.cap + k] = uvec2(q, floatBitsToUint(divergence(r, c)));
        }
        return;
    }
    const uint n = count[p.colour], base = uint(p.colour) * p.cap;
    for (uint i = gl_GlobalInvocationID.x; i < n; i += lanes) {
        const uvec2 e = list[base + i];
        const uint q = e.x;
        const int r = int(q / uint(p.W)), c = int(q % uint(p.W));
        const int inside = int(r > 0) + int(r + 1 < p.H) + int(c > 0) + int(c + 1 < p.W);
        const vec2 gq = grad[q];
        precise float nb = ((r > 0 ? z[q - uint(p.W)] : -gq.x) + (r + 1 < p.H ? z[q + uint(p.W)] : gq.x)) +
                           ((c > 0 ? z[q - 1u] : -gq.y) + (c + 1 < p.W ? z[q + 1u] : gq.y));
        precise float v = (1.0 - p.omega) * z[q] + p.omega * ((nb - uintBitsToFloat(e.y)) / float(inside));
        z[q] = v;
    }
}
