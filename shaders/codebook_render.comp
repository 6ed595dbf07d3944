#version 450
// Render-and-compare: each surface sample's height map (engine/ops/codebook.cpp says
// what; engine/ops/codebook_math.h is the CPU mirror, operation for operation). A
// workgroup per sample: its cells start at the cap, its invocations splat the points
// of the 27 bins around the sample with an atomic minimum over order-preserving bits,
// then turn the bits back into depths. The arithmetic is `precise` (no fused
// multiply-adds), so a point covers the same cells as on the CPU.
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Samples_ { float smp[]; };  // [S, 9]
layout(std430, binding = 1) readonly buffer Points_ { float pts[]; };   // [D, 6]
layout(std430, binding = 2) readonly buffer Bins_ { int bins[]; };      // [nx*ny*nz, 2]
layout(std430, binding = 3) coherent buffer Out_ { uint book[]; };      // [S, G*G]
layout(push_constant) uniform Push {
    int S; int G;
    float inv_cell; float splat; float cap; float facing;
    float ox; float oy; float oz; float inv_coarse;
    int nx; int ny; int nz;
} p;

float dot3(vec3 a, vec3 b) { precise float r = (a.x * b.x + a.y * b.y) + a.z * b.z; return r; }
vec3 cross3(vec3 a, vec3 b) {
    precise vec3 r = vec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
    return r;
}
uint ordered(float f) { uint u = floatBitsToUint(f); return (u & 0x80000000u) != 0u ? ~u : (u | 0x80000000u); }
float unordered(uint u) { return uintBitsToFloat((u & 0x80000000u) != 0u ? (u & 0x7fffffffu) : ~u); }
int coarse_index(float v, float o, int n) {
    precise float q = floor((v - o) * p.inv_coarse);
    return int(clamp(q, 0.0, float(n - 1)));
}

void main() {
    const uint GG = uint(p.G) * uint(p.G), L = gl_WorkGroupSize.x, lid = gl_LocalInvocationID.x;
    const uint D = uint(pts.length()) / 6u;
    for (uint s = gl_WorkGroupID.x; s < uint(p.S); s += gl_NumWorkGroups.x) {
        const uint base = s * GG;
        for (uint c = lid; c < GG; c += L) book[base + c] = ordered(p.cap);
        memoryBarrierBuffer();
        barrier();
        const vec3 ps = vec3(smp[9u * s], smp[9u * s + 1u], smp[9u * s + 2u]);
        precise vec3 z = vec3(smp[9u * s + 3u], smp[9u * s + 4u], smp[9u * s + 5u]) * -1.0;
        const vec3 t1 = vec3(smp[9u * s + 6u], smp[9u * s + 7u], smp[9u * s + 8u]);
        const vec3 t2 = cross3(z, t1);
        precise float half_ = float(p.G - 1) * 0.5;
        precise float rc = p.splat * p.inv_cell;
        const int cx = coarse_index(ps.x, p.ox, p.nx), cy = coarse_index(ps.y, p.oy, p.ny), cz = coarse_index(ps.z, p.oz, p.nz);
        for (int bz = max(0, cz - 1); bz <= min(p.nz - 1, cz + 1); ++bz)
            for (int by = max(0, cy - 1); by <= min(p.ny - 1, cy + 1); ++by)
                for (int bx = max(0, cx - 1); bx <= min(p.nx - 1, cx + 1); ++bx) {
                    const int bin = (bz * p.ny + by) * p.nx + bx;
                    const uint first = uint(bins[2 * bin]), end = min(D, first + uint(bins[2 * bin + 1]));
                    for (uint k = first + lid; k < end; k += L) {
                        precise vec3 d = vec3(pts[6u * k], pts[6u * k + 1u], pts[6u * k + 2u]) - ps;
                        const vec3 nq = vec3(pts[6u * k + 3u], pts[6u * k + 4u], pts[6u * k + 5u]);
                        const float h = dot3(d, z);
                        if (abs(h) > p.cap || dot3(nq, z) > p.facing) continue;
                        precise float fa = dot3(d, t1) * p.inv_cell + half_, fb = dot3(d, t2) * p.inv_cell + half_;
                        const int i0 = max(0, int(ceil(fa - rc))), i1 = min(p.G - 1, int(floor(fa + rc)));
                        const int j0 = max(0, int(ceil(fb - rc))), j1 = min(p.G - 1, int(floor(fb + rc)));
                        const uint v = ordered(h);
                        for (int j = j0; j <= j1; ++j)
                            for (int i = i0; i <= i1; ++i) {
                                precise float da = float(i) - fa, db = float(j) - fb;
                                precise float r2 = da * da + db * db, lim = rc * rc;
                                if (r2 <= lim) atomicMin(book[base + uint(j * p.G + i)], v);
                            }
                    }
                }
        memoryBarrierBuffer();
        barrier();
        for (uint c = lid; c < GG; c += L) book[base + c] = floatBitsToUint(unordered(book[base + c]));
        memoryBarrierBuffer();
        barrier();
    }
}
