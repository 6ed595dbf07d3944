#version 450
// Normals by k nearest neighbours + PCA (engine/ops/normal_estimate.cpp has
// the contract). One thread per point; the k best (squared distance, index)
// kept sorted in registers; the grid searched ring by ring with the CPU
// reference's stopping rule, so both choose the same neighbours. PCA in fp32.
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint K = 16;

layout(std430, binding = 0) readonly buffer Points_ { float x[]; };     // [N, D]
layout(std430, binding = 1) readonly buffer Order_ { int order[]; };    // [N]
layout(std430, binding = 2) readonly buffer Start_ { int cstart[]; };   // [G + 1]
layout(std430, binding = 3) writeonly buffer Out_ { float nrm[]; };     // [N, 3]
layout(push_constant) uniform Push {
    uint N, D, gx, gy, gz, orient;
    float cell, ox, oy, oz, rx, ry, rz;
} p;

vec3 point(uint i) { return vec3(x[i * p.D], x[i * p.D + 1u], x[i * p.D + 2u]); }

// As sqdist3 (point_common.h): one rounding per operation, no fma.
float sqdist(vec3 a, vec3 c) {
    precise float dx = a.x - c.x, dy = a.y - c.y, dz = a.z - c.z;
    precise float xx = dx * dx, yy = dy * dy, zz = dz * dz;
    precise float xy = xx + yy;
    precise float r = xy + zz;
    return r;
}

float bd[K];
int bi[K];
uint found;

void consider(float d, int j) {
    if (found == K && !(d < bd[K - 1u] || (d == bd[K - 1u] && j < bi[K - 1u]))) return;
    uint pos = found < K ? found : K - 1u;
    while (pos > 0u && (d < bd[pos - 1u] || (d == bd[pos - 1u] && j < bi[pos - 1u]))) {
        bd[pos] = bd[pos - 1u];
        bi[pos] = bi[pos - 1u];
        pos--;
    }
    bd[pos] = d;
    bi[pos] = j;
    if (found < K) found++;
}

// Eigenvector of the smallest eigenvalue (as smallest_eigenvector in the .cpp).
vec3 smallest_eigenvector(mat3 A) {
    float p1 = A[0][1] * A[0][1] + A[0][2] * A[0][2] + A[1][2] * A[1][2];
    float q = (A[0][0] + A[1][1] + A[2][2]) / 3.0;
    float p2 = (A[0][0] - q) * (A[0][0] - q) + (A[1][1] - q) * (A[1][1] - q) + (A[2][2] - q) * (A[2][2] - q) + 2.0 * p1;
    float pp = sqrt(p2 / 6.0);
    if (!(pp > 0.0)) return vec3(uintBitsToFloat(0x7fc00000u));
    // A line: as the .cpp, by the principal 2x2 minors (acos near 1 is coarse in fp32).
    float tr = A[0][0] + A[1][1] + A[2][2];
    float m2 = A[0][0] * A[1][1] - A[0][1] * A[0][1] + A[0][0] * A[2][2] - A[0][2] * A[0][2] + A[1][1] * A[2][2] -
               A[1][2] * A[1][2];
    if (!(m2 > 1e-4 * tr * tr)) return vec3(uintBitsToFloat(0x7fc00000u));
    mat3 B = (A - q * mat3(1.0)) / pp;
    float phi = acos(clamp(determinant(B) / 2.0, -1.0, 1.0)) / 3.0;
    float big = q + 2.0 * pp * cos(phi);
    float lambda = q + 2.0 * pp * cos(phi + 2.0943951);
    mat3 M = A - lambda * mat3(1.0);
    // rows of the symmetric M are its columns
    vec3 c01 = cross(M[0], M[1]), c02 = cross(M[0], M[2]), c12 = cross(M[1], M[2]);
    float n01 = dot(c01, c01), n02 = dot(c02, c02), n12 = dot(c12, c12);
    vec3 v = c01;
    float n = n01;
    if (n02 > n) { v = c02; n = n02; }
    if (n12 > n) { v = c12; n = n12; }
    if (!(sqrt(n) > 1e-6 * big * big)) return vec3(uintBitsToFloat(0x7fc00000u));
    return v / sqrt(n);
}

void main() {
    const uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    const ivec3 dims = ivec3(p.gx, p.gy, p.gz);
    const vec3 org = vec3(p.ox, p.oy, p.oz);
    for (uint i = gl_GlobalInvocationID.x; i < p.N; i += stride) {
        const vec3 pi = point(i);
        const ivec3 c = clamp(ivec3(floor((pi - org) / p.cell)), ivec3(0), dims - 1);
        found = 0u;
        const int max_r = max(dims.x, max(dims.y, dims.z));
        for (int r = 0; r <= max_r; ++r) {
            for (int dz = -r; dz <= r; ++dz)
                for (int dy = -r; dy <= r; ++dy)
                    for (int dx = -r; dx <= r; ++dx) {
                        if (max(abs(dx), max(abs(dy), abs(dz))) != r) continue;
                        ivec3 cc = c + ivec3(dx, dy, dz);
                        if (any(lessThan(cc, ivec3(0))) || any(greaterThanEqual(cc, dims))) continue;
                        int cell = (cc.z * dims.y + cc.y) * dims.x + cc.x;
                        for (int s = cstart[cell]; s < cstart[cell + 1]; ++s) {
                            int j = order[s];
                            consider(sqdist(pi, point(uint(j))), j);
                        }
                    }
            precise float lim = (float(r) - 0.5) * p.cell;
            precise float lim2 = lim * lim;
            if (found == K && lim > 0.0 && bd[K - 1u] <= lim2) break;
        }
        vec3 m = vec3(0.0);
        for (uint t = 0u; t < K; ++t) m += point(uint(bi[t])) - pi;
        m /= float(K);
        mat3 C = mat3(0.0);
        for (uint t = 0u; t < K; ++t) {
            vec3 d = point(uint(bi[t])) - pi - m;
            C += outerProduct(d, d) / float(K);
        }
        vec3 n = smallest_eigenvector(C);
        if (p.orient != 0u) {
            float s = (p.orient == 1u ? 1.0 : -1.0) * dot(n, pi - vec3(p.rx, p.ry, p.rz));
            if (s < 0.0) n = -n;
        }
        nrm[i * 3u] = n.x;
        nrm[i * 3u + 1u] = n.y;
        nrm[i * 3u + 2u] = n.z;
    }
}
