#version 450
// The gel's contact mask, one stage per dispatch (engine/ops/gel_contact_mask.cpp lists them;
// CPU mirror engine/ops/gel_mask.h). A lane owns one 32-pixel word of a row: images are bit rows,
// so the disc's morphology is shifts and ORs of a few words, and a lane walks runs, not pixels.
// The stage is a specialization constant: a CPU driver runs every branch of a run-time switch
// under lane masks, so each dispatch would cost all of them.
//
// Hole fill and labelling are union-find over each word's runs of equal pixels (a run's pixels
// point at its first). Parents always point to a smaller index, so a piece's root is its first
// pixel in raster order whatever order the lanes ran in, and hooking (compare-and-swap on a
// root) never waits on another lane: no stage loops to convergence.
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const int kStage = 0;
layout(std430, binding = 0) readonly buffer Grad_ { float grad[]; };   // [H, W, 2]
layout(std430, binding = 1) writeonly buffer Mask_ { float mask[]; };  // [H, W]
// Bit images A and B, two sets of parents and counts [H W] each, the largest count and its root.
layout(std430, binding = 2) coherent buffer Ws_ { uint ws[]; };
// src, dst: image bases; uf: the parents of this stage's union-find (its counts follow them);
// init: the parents to reset for the next one from the word written, or ~0u.
layout(push_constant) uniform Push { int H; int W; int radius; uint src; uint dst; uint uf; uint init; uint top; float threshold; } p;

const int kSlope = 0, kDilate = 1, kErode = 2, kJoinBackground = 3, kJoinForeground = 4, kMarkOutside = 5, kFillHoles = 6,
          kFillHolesOut = 7, kCount = 8, kFirstLargest = 9, kKeepLargest = 10;

uint NW() { return (uint(p.W) + 31u) / 32u; }
uint HW() { return uint(p.H) * uint(p.W); }
uint valid(int k) { const int rest = p.W - 32 * k; return rest >= 32 ? 0xffffffffu : (1u << uint(rest)) - 1u; }

// Word k of row y of the image at base (its complement within the image when inv), 0 outside.
uint word_at(uint base, int y, int k, bool inv) {
    if (k < 0 || k >= int(NW())) return 0u;
    const uint w = ws[base + uint(y) * NW() + uint(k)];
    return inv ? ~w & valid(k) : w;
}

// Pixels start .. start + 31 of row y as a word (start may be negative).
uint bits_at(uint base, int y, int start, bool inv) {
    const int k = start >> 5;
    const uint off = uint(start & 31), lo = word_at(base, y, k, inv);
    return off == 0u ? lo : (lo >> off) | (word_at(base, y, k + 1, inv) << (32u - off));
}

float slope_at(int y, int x) {
    const uint q = uint(y) * uint(p.W) + uint(x);
    const float a = grad[2u * q], b = grad[2u * q + 1u];
    precise float s = a * a + b * b;
    precise float m = sqrt(s);
    return m;
}

// The word's pixels whose 3x3 mean slope (edges repeated) passes the threshold, in the
// reference's order: each row left to right, then the rows top to bottom, times 1/9.
uint steep_word(int y, int k) {
    const int y0 = max(y - 1, 0), y2 = min(y + 1, p.H - 1), x0 = 32 * k, x1 = min(x0 + 32, p.W);
    vec3 left = vec3(slope_at(y0, max(x0 - 1, 0)), slope_at(y, max(x0 - 1, 0)), slope_at(y2, max(x0 - 1, 0)));
    vec3 mid = vec3(slope_at(y0, x0), slope_at(y, x0), slope_at(y2, x0));
    uint out_bits = 0u;
    for (int x = x0; x < x1; ++x) {
        const int xr = min(x + 1, p.W - 1);
        const vec3 right = vec3(slope_at(y0, xr), slope_at(y, xr), slope_at(y2, xr));
        precise vec3 rows = (left + mid) + right;
        precise float sum = (rows.x + rows.y) + rows.z;
        precise float mean = sum * (1.0 / 9.0);
        if (mean > p.threshold) out_bits |= 1u << uint(x - x0);
        left = mid, mid = right;
    }
    return out_bits;
}

// Dilation (inv false) or erosion (inv true: the complement dilated) by the disc, reading only
// pixels inside the image.
uint morph_word(int y, int k, bool inv) {
    const int r = p.radius;
    uint acc = 0u;
    for (int dy = max(-r, -y); dy <= min(r, p.H - 1 - y); ++dy) {
        int w = int(sqrt(float(r * r - dy * dy)));  // the disc's half-width in row dy, made exact
        if ((w + 1) * (w + 1) + dy * dy <= r * r) ++w;
        if (w * w + dy * dy > r * r) --w;
        for (int dx = -w; dx <= w; ++dx) acc |= bits_at(p.src, y + dy, 32 * k + dx, inv);
    }
    return (inv ? ~acc : acc) & valid(k);
}

uint parent(uint q) { return ws[p.uf + q]; }
uint count_of(uint q) { return ws[p.uf + HW() + q]; }

// The root, read only: stages that store it run while other lanes still walk through.
uint root_of(uint q) {
    uint up = parent(q);
    while (up != q) q = up, up = parent(q);
    return q;
}

// The root, each step pointing the node behind at its grandparent (an ancestor all the same).
uint find(uint q) {
    uint prev = q, cur = parent(q), next;
    while (cur > (next = parent(cur))) {
        ws[p.uf + prev] = next;
        prev = cur, cur = next;
    }
    return cur;
}

void unite(uint a, uint b) {
    a = find(a), b = find(b);
    while (a != b) {
        if (a < b) { const uint t = a; a = b; b = t; }
        const uint was = atomicCompSwap(ws[p.uf + a], a, b);  // hook the larger root under the smaller
        if (was == a) return;
        a = find(was), b = find(b);
    }
}

// The next run at or after bit `from` of `bits`: its first bit (32: none) and its length.
int run_from(uint bits, int from, out int len) {
    const uint rest = from >= 32 ? 0u : bits & (0xffffffffu << uint(from));
    if (rest == 0u) { len = 0; return 32; }
    const int b = findLSB(rest), e = findLSB(~(bits | ((1u << uint(b)) - 1u)));
    len = (e < 0 ? 32 : e) - b;
    return b;
}

// Parents for the next union-find from a word just written: each run of equal pixels of the
// word points at its first pixel, and counts are zeroed.
void init_word(int y, int k, uint bits) {
    if (p.init == 0xffffffffu) return;
    const uint q0 = uint(y) * uint(p.W) + uint(32 * k), n = uint(min(32, p.W - 32 * k));
    uint start = 0u;
    for (uint b = 0u; b < n; ++b) {
        if (b > 0u && ((bits >> b) & 1u) != ((bits >> (b - 1u)) & 1u)) start = b;
        ws[p.init + q0 + b] = q0 + start, ws[p.init + HW() + q0 + b] = 0u;
    }
}

void store_word(int y, int k, uint bits) {
    ws[p.dst + uint(y) * NW() + uint(k)] = bits;
    init_word(y, k, bits);
}

// Pieces of `value` (the image at src): word-crossing runs joined, and each run overlapping the
// row above once per stretch of overlap.
void join(int y, int k, bool value) {
    const uint q = uint(y) * uint(p.W) + uint(32 * k), here = word_at(p.src, y, k, !value);
    if (k > 0 && (here & 1u) != 0u && (word_at(p.src, y, k - 1, !value) >> 31) != 0u) unite(q, q - 1u);
    if (y == 0) return;
    const uint both = here & word_at(p.src, y - 1, k, !value);
    for (uint starts = both & ~(both << 1); starts != 0u; starts &= starts - 1u) {
        const uint b = uint(findLSB(starts));
        unite(q + b, q + b - uint(p.W));
    }
}

// Background runs: their roots stored (each lane its own runs' first pixels), and the roots of
// those on the image's border marked (counts = 1).
void mark_outside(int y, int k) {
    const uint q = uint(y) * uint(p.W) + uint(32 * k), bg = word_at(p.src, y, k, true);
    int len;
    for (int b = run_from(bg, 0, len); b < 32; b = run_from(bg, b + len, len)) {
        const uint root = root_of(q + uint(b));
        ws[p.uf + q + uint(b)] = root;
        if (y == 0 || y == p.H - 1 || 32 * k + b == 0 || 32 * k + b + len == p.W) ws[p.uf + HW() + root] = 1u;
    }
}

// The image with its holes (background runs whose root is unmarked) filled.
uint filled_word(int y, int k) {
    const uint q = uint(y) * uint(p.W) + uint(32 * k), bg = word_at(p.src, y, k, true);
    uint out_bits = ~bg & valid(k);
    int len;
    for (int b = run_from(bg, 0, len); b < 32; b = run_from(bg, b + len, len))
        if (count_of(parent(q + uint(b))) == 0u) out_bits |= (len == 32 ? 0xffffffffu : ((1u << uint(len)) - 1u)) << uint(b);
    return out_bits;
}

void main() {
    const uint words = uint(p.H) * NW(), stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint i = gl_GlobalInvocationID.x; i < words; i += stride) {
        const int y = int(i / NW()), k = int(i % NW());
        const uint q = uint(y) * uint(p.W) + uint(32 * k);
        const uint fg = kStage >= kCount ? word_at(p.src, y, k, false) : 0u;
        int len;
        if (kStage == kSlope) store_word(y, k, steep_word(y, k));
        if (kStage == kDilate) store_word(y, k, morph_word(y, k, false));
        if (kStage == kErode) store_word(y, k, morph_word(y, k, true));
        if (kStage == kJoinBackground) join(y, k, false);
        if (kStage == kJoinForeground) join(y, k, true);
        if (kStage == kMarkOutside) {
            mark_outside(y, k);
            if (i == 0u) ws[p.top] = 0u, ws[p.top + 1u] = 0xffffffffu;  // for the labelling, which comes after the first fill
        }
        if (kStage == kFillHoles) store_word(y, k, filled_word(y, k));
        if (kStage == kFillHolesOut) {
            const uint bits = filled_word(y, k);
            for (int b = 0; b < min(32, p.W - 32 * k); ++b) mask[q + uint(b)] = float((bits >> uint(b)) & 1u);
        }
        if (kStage == kCount)  // each foreground run's root stored, its length added to the root's count
            for (int b = run_from(fg, 0, len); b < 32; b = run_from(fg, b + len, len)) {
                const uint root = root_of(q + uint(b));
                ws[p.uf + q + uint(b)] = root;
                atomicMax(ws[p.top], atomicAdd(ws[p.uf + HW() + root], uint(len)) + uint(len));
            }
        if (kStage == kFirstLargest)
            for (int b = run_from(fg, 0, len); b < 32; b = run_from(fg, b + len, len))
                if (parent(q + uint(b)) == q + uint(b) && count_of(q + uint(b)) == ws[p.top]) atomicMin(ws[p.top + 1u], q + uint(b));
        if (kStage == kKeepLargest) {
            uint kept = 0u;
            for (int b = run_from(fg, 0, len); b < 32; b = run_from(fg, b + len, len))
                if (parent(q + uint(b)) == ws[p.top + 1u]) kept |= (len == 32 ? 0xffffffffu : ((1u << uint(len)) - 1u)) << uint(b);
            store_word(y, k, kept);
        }
    }
}
