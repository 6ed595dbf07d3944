#version 450
// lap(z) = div(grad) inside the mask, z = 0 outside it in the image, the image's border free (a
// ghost neighbour continues the gradient): red-black SOR (engine/ops/gel_shape.cpp; CPU mirror
// engine/ops/gel_ops.h). One workgroup, a barrier between colours: within a colour the
// updates read only the other colour, so the result is the reference's in any lane order.
layout(local_size_x_id = 0) in;
layout(std430, binding = 0) readonly buffer Grad_ { float grad[]; };  // [H, W, 2]
layout(std430, binding = 1) readonly buffer Mask_ { float mask[]; };  // [H, W]
layout(std430, binding = 2) buffer Z_ { float z[]; };                 // [H, W]
layout(push_constant) uniform Push { int H; int W; int iterations; float omega; } p;

float g(int r, int c, int k) { return grad[(uint(r) * uint(p.W) + uint(c)) * 2u + uint(k)]; }

float divergence(int r, int c) {
    precise float dr = p.H == 1 ? 0.0 : r == 0 ? g(1, c, 0) - g(0, c, 0)
                     : r == p.H - 1 ? g(r, c, 0) - g(r - 1, c, 0) : 0.5 * (g(r + 1, c, 0) - g(r - 1, c, 0));
    precise float dc = p.W == 1 ? 0.0 : c == 0 ? g(r, 1, 1) - g(r, 0, 1)
                     : c == p.W - 1 ? g(r, c, 1) - g(r, c - 1, 1) : 0.5 * (g(r, c + 1, 1) - g(r, c - 1, 1));
    precise float s = dr + dc;
    return s;
}

void main() {
    const uint HW = uint(p.H) * uint(p.W), L = gl_WorkGroupSize.x;
    for (uint q = gl_LocalInvocationID.x; q < HW; q += L) z[q] = 0.0;
    memoryBarrierBuffer();
    barrier();
    for (int half_sweep = 0; half_sweep < 2 * p.iterations; ++half_sweep) {
        const int colour = half_sweep & 1;
        for (uint q = gl_LocalInvocationID.x; q < HW; q += L) {
            const int r = int(q / uint(p.W)), c = int(q % uint(p.W));
            if (((r + c) & 1) != colour || !(mask[q] > 0.5)) continue;
            const int inside = int(r > 0) + int(r + 1 < p.H) + int(c > 0) + int(c + 1 < p.W);
            if (inside == 0) continue;
            const float gr = grad[2u * q], gc = grad[2u * q + 1u];
            precise float nb = ((r > 0 ? z[q - uint(p.W)] : -gr) + (r + 1 < p.H ? z[q + uint(p.W)] : gr)) +
                               ((c > 0 ? z[q - 1u] : -gc) + (c + 1 < p.W ? z[q + 1u] : gc));
            precise float v = (1.0 - p.omega) * z[q] + p.omega * ((nb - divergence(r, c)) / float(inside));
            z[q] = v;
        }
        memoryBarrierBuffer();
        barrier();
    }
}
