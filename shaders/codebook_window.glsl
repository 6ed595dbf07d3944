// Shared by codebook_window_min.comp and codebook_score.comp: a sample's map read
// under a window cell at a spin, from its bilinear quads (one vec4 read instead of
// four gathers), in the fp32 order of engine/ops/codebook_math.h (window_depth,
// quad_at). The includer declares LOAD_QUAD(i) (vec4 i of [S, (G+1)^2]) and the push
// constants' G, R, C, inv_cell, win, cap as `p`.

float quad_at(uint base, float fa, float fb) {
    const float a0 = floor(fa), b0 = floor(fb);
    precise float wa = fa - a0, wb = fb - b0;
    const int i = int(a0), j = int(b0);
    const bool inside = i >= -1 && j >= -1 && i < p.G && j < p.G;
    // Always read (a clamped entry), then select: a read under a branch costs lavapipe as much.
    const vec4 t = LOAD_QUAD(base + uint(inside ? (j + 1) * (p.G + 1) + (i + 1) : 0));
    const vec4 q = inside ? t : vec4(p.cap);
    precise float top = q.x * (1.0 - wa) + q.y * wa;
    precise float bot = q.z * (1.0 - wa) + q.w * wa;
    precise float r = top * (1.0 - wb) + bot * wb;
    return r;
}

float window_depth(uint base, float cs, float sn, int r, int c) {
    const float hr = float(p.R - 1) * 0.5, hc = float(p.C - 1) * 0.5, half_ = float(p.G - 1) * 0.5;
    precise float u = (float(c) - hc) * p.win, v = (float(r) - hr) * p.win;
    precise float a = u * cs - v * sn, b = u * sn + v * cs;
    precise float fa = a * p.inv_cell + half_, fb = b * p.inv_cell + half_;
    return quad_at(base, fa, fb);
}
