// The register-resident ILU of ilu_wave.comp and ilu_retrieve.comp: the whole
// ILU (SPEC 2) in one dispatch, one workgroup per touch, with no
// shared memory and no barrier where the workgroup is one subgroup.
// Why: on a CPU driver (lavapipe) a workgroup runs on one core, every storage
// or shared-memory load is a loop over the lanes and every barrier a context
// switch, while a texel fetch is one gather and a shuffle by a uniform index is
// a register broadcast. So the state lives in registers: lane t owns the row
// blocks t, t + L, ... (4 rows each) of h and the gates, each matvec reads its
// weights as vec4 texels (4 inputs of one row) and gets the input vector's
// block kb from its owner by subgroupShuffle. Where the workgroup spans more
// than one subgroup (a device whose compute subgroups are narrower than asked,
// or the tests' forced width) the blocks travel through shared memory instead.
// Needs C and H divisible by 4 (the host picks ilu.comp otherwise).
// The includer declares the workgroup size (spec constant 0), the push
// constant block p with a member max_iters, and includes act.glsl first.
layout(constant_id = 1) const uint C = 16;   // hidden size
layout(constant_id = 2) const uint H = 16;   // head hidden size
layout(constant_id = 3) const uint RB = 1;   // row blocks per lane for C rows: ceil(C / 4 / L)
layout(constant_id = 4) const uint HB = 1;   // the same for H rows

layout(std430, binding = 0) readonly buffer Ft_ { float ft[]; };
layout(std430, binding = 1) readonly buffer Fp_ { float fp[]; };
layout(std430, binding = 2) readonly buffer Iters_ { int iters; };
layout(binding = 3) uniform samplerBuffer Wz;  // [C, 3C] as vec4s
layout(std430, binding = 4) readonly buffer Bz_ { float bz[]; };
layout(binding = 5) uniform samplerBuffer Wr;
layout(std430, binding = 6) readonly buffer Br_ { float br[]; };
layout(binding = 7) uniform samplerBuffer Wq;
layout(std430, binding = 8) readonly buffer Bq_ { float bq[]; };
layout(binding = 9) uniform samplerBuffer W0;  // [H, C] as vec4s
layout(std430, binding = 10) readonly buffer B0_ { float b0[]; };
layout(binding = 11) uniform samplerBuffer W2;  // [3, H] as floats
layout(std430, binding = 12) readonly buffer B2_ { float b2[]; };
layout(std430, binding = 13) writeonly buffer Cs_ { float cs[]; };            // [B, Nmax, 3]
layout(std430, binding = 14) writeonly buffer Contact_ { float contact[]; };  // [B, 3]

const uint L = gl_WorkGroupSize.x;
const uint CB = C / 4u, HBLK = H / 4u, C3B = 3u * C / 4u;

shared vec4 blocks[CB];  // the multi-subgroup path's copy of the vector being read
shared vec3 partial[L];

#define t gl_LocalInvocationID.x
#define ft_row (gl_WorkGroupID.x * C)

bool one_subgroup() { return gl_NumSubgroups == 1u; }

// Every lane's copy of block kb of a vector held as v[m] = block t + L m.
#define BLOCK(v, kb) (one_subgroup() ? subgroupShuffle(v[(kb) / L], (kb) % L) : blocks[kb])

// Multi-subgroup path: makes v's blocks readable by BLOCK (uniform control flow).
#define PUBLISH(v)                                              \
    if (!one_subgroup()) {                                      \
        barrier();                                              \
        for (uint m = 0u; m < RB; ++m)                          \
            if (t + L * m < CB) blocks[t + L * m] = v[m];       \
        barrier();                                              \
    }

vec4 h[RB], gz[RB], gr[RB], gq[RB];
vec4 b0v[HB];

vec4 ld4(uint i) { return vec4(ft[ft_row + i], ft[ft_row + i + 1u], ft[ft_row + i + 2u], ft[ft_row + i + 3u]); }
vec4 fp4(uint i) { return vec4(fp[i], fp[i + 1u], fp[i + 2u], fp[i + 3u]); }
vec4 bias4(uint which, uint i) {
    if (which == 0u) return vec4(bz[i], bz[i + 1u], bz[i + 2u], bz[i + 3u]);
    if (which == 1u) return vec4(br[i], br[i + 1u], br[i + 2u], br[i + 3u]);
    return vec4(bq[i], bq[i + 1u], bq[i + 2u], bq[i + 3u]);
}

// Rows 4 rb .. 4 rb + 3 of W [rows, 3C] times the 4 inputs of column block kb.
vec4 rows4(samplerBuffer W, uint rb, uint kb, vec4 x) {
    uint r = 4u * rb * C3B + kb;
    return vec4(dot(texelFetch(W, int(r)), x), dot(texelFetch(W, int(r + C3B)), x),
                dot(texelFetch(W, int(r + 2u * C3B)), x), dot(texelFetch(W, int(r + 3u * C3B)), x));
}

// h_0 = tanh(F^t) and the x half of the gates plus bias (the same every iteration).
void init() {
    for (uint m = 0u; m < RB; ++m) {
        uint rb = t + L * m;
        if (rb >= CB) break;
        vec4 f = ld4(4u * rb);
        for (uint i = 0u; i < 4u; ++i) h[m][i] = apply_act(f[i], ACT_TANH, 0.0);
        gz[m] = bias4(0u, 4u * rb);
        gr[m] = bias4(1u, 4u * rb);
        gq[m] = bias4(2u, 4u * rb);
    }
    for (uint kb = 0u; kb < 2u * CB; ++kb) {  // x = [F^p, ReLU(F^t)], read by every lane
        vec4 x = kb < CB ? fp4(4u * kb) : max(ld4(4u * (kb - CB)), vec4(0.0));
        for (uint m = 0u; m < RB; ++m) {
            uint rb = t + L * m;
            if (rb >= CB) break;
            gz[m] += rows4(Wz, rb, CB + kb, x);
            gr[m] += rows4(Wr, rb, CB + kb, x);
            gq[m] += rows4(Wq, rb, CB + kb, x);
        }
    }
    for (uint m = 0u; m < HB; ++m) {
        uint rb = t + L * m;
        if (rb < HBLK) b0v[m] = vec4(b0[4u * rb], b0[4u * rb + 1u], b0[4u * rb + 2u], b0[4u * rb + 3u]);
    }
}

vec4 sigmoid4(vec4 v) {
    return vec4(apply_act(v.x, ACT_SIGMOID, 0.0), apply_act(v.y, ACT_SIGMOID, 0.0), apply_act(v.z, ACT_SIGMOID, 0.0),
                apply_act(v.w, ACT_SIGMOID, 0.0));
}
vec4 tanh4(vec4 v) {
    return vec4(apply_act(v.x, ACT_TANH, 0.0), apply_act(v.y, ACT_TANH, 0.0), apply_act(v.z, ACT_TANH, 0.0),
                apply_act(v.w, ACT_TANH, 0.0));
}

// One GRU update of h; returns this lane's share of c's increment (summed by the caller).
vec3 iteration() {
    vec4 z[RB], rh[RB];
    for (uint m = 0u; m < RB; ++m) { z[m] = vec4(0.0); rh[m] = vec4(0.0); }
    PUBLISH(h)
    for (uint kb = 0u; kb < CB; ++kb) {
        vec4 hk = BLOCK(h, kb);
        for (uint m = 0u; m < RB; ++m) {
            uint rb = t + L * m;
            if (rb >= CB) break;
            z[m] += rows4(Wz, rb, kb, hk);
            rh[m] += rows4(Wr, rb, kb, hk);
        }
    }
    for (uint m = 0u; m < RB; ++m) {
        z[m] = sigmoid4(z[m] + gz[m]);
        rh[m] = sigmoid4(rh[m] + gr[m]) * h[m];  // r * h
    }
    vec4 q[RB];
    for (uint m = 0u; m < RB; ++m) q[m] = vec4(0.0);
    PUBLISH(rh)
    for (uint kb = 0u; kb < CB; ++kb) {
        vec4 xk = BLOCK(rh, kb);
        for (uint m = 0u; m < RB; ++m) {
            uint rb = t + L * m;
            if (rb >= CB) break;
            q[m] += rows4(Wq, rb, kb, xk);
        }
    }
    for (uint m = 0u; m < RB; ++m) h[m] = (1.0 - z[m]) * h[m] + z[m] * tanh4(q[m] + gq[m]);
    // c += Linear(H, 3)(ReLU(Linear(C, H)(h))): each lane its hidden rows.
    vec4 hid[HB];
    for (uint m = 0u; m < HB; ++m) hid[m] = vec4(0.0);
    PUBLISH(h)
    for (uint kb = 0u; kb < CB; ++kb) {
        vec4 hk = BLOCK(h, kb);
        for (uint m = 0u; m < HB; ++m) {
            uint rb = t + L * m;
            if (rb >= HBLK) break;
            uint r = 4u * rb * CB + kb;
            hid[m] += vec4(dot(texelFetch(W0, int(r)), hk), dot(texelFetch(W0, int(r + CB)), hk),
                           dot(texelFetch(W0, int(r + 2u * CB)), hk), dot(texelFetch(W0, int(r + 3u * CB)), hk));
        }
    }
    vec3 d = vec3(0.0);
    for (uint m = 0u; m < HB; ++m) {
        uint rb = t + L * m;
        if (rb >= HBLK) break;
        vec4 a = max(hid[m] + b0v[m], vec4(0.0));
        for (uint i = 0u; i < 4u; ++i)
            d += a[i] * vec3(texelFetch(W2, int(4u * rb + i)).x, texelFetch(W2, int(H + 4u * rb + i)).x,
                             texelFetch(W2, int(2u * H + 4u * rb + i)).x);
    }
    return d;
}

// Sum of every lane's v, in every lane (uniform control flow).
vec3 workgroup_sum(vec3 v) {
    if (one_subgroup()) {
        for (uint o = 1u; o < L; o <<= 1u) v += subgroupShuffleXor(v, o);  // L is a power of two
        return v;
    }
    barrier();
    partial[t] = v;
    barrier();
    vec3 s = vec3(0.0);
    for (uint i = 0u; i < L; ++i) s += partial[i];
    return s;
}

// Runs the ILU and writes cs and contact; returns c_N, the same in every lane.
vec3 ilu_wave_run() {
    init();
    const uint n = uint(clamp(iters, 0, int(p.max_iters)));
    const uint cs0 = gl_WorkGroupID.x * p.max_iters * 3u;
    vec3 c = vec3(0.0), b2v = vec3(b2[0], b2[1], b2[2]);
    for (uint it = 0u; it < n; ++it) {
        c += workgroup_sum(iteration()) + b2v;
        if (t == 0u) {
            cs[cs0 + it * 3u] = c.x;
            cs[cs0 + it * 3u + 1u] = c.y;
            cs[cs0 + it * 3u + 2u] = c.z;
        }
    }
    for (uint i = n * 3u + t; i < p.max_iters * 3u; i += L) cs[cs0 + i] = 0.0;
    if (t == 0u) {
        contact[gl_WorkGroupID.x * 3u] = c.x;
        contact[gl_WorkGroupID.x * 3u + 1u] = c.y;
        contact[gl_WorkGroupID.x * 3u + 2u] = c.z;
    }
    return c;
}

#undef t
#undef ft_row
