// Activation functions shared by activation.comp and the fused GEMM epilogue.
// Codes match engine/ops/common.h (Act).
#define ACT_NONE 0u
#define ACT_RELU 1u
#define ACT_LEAKY 2u
#define ACT_TANH 3u
#define ACT_SIGMOID 4u

float apply_act(float v, uint act, float slope) {
    if (act == ACT_RELU) return max(v, 0.0);
    if (act == ACT_LEAKY) return v >= 0.0 ? v : v * slope;
    if (act == ACT_TANH) {
        // exp of a non-positive number never overflows, unlike the textbook form
        float e = exp(-2.0 * abs(v));
        return sign(v) * (1.0 - e) / (1.0 + e);
    }
    if (act == ACT_SIGMOID) {
        float e = exp(-abs(v));
        return v >= 0.0 ? 1.0 / (1.0 + e) : e / (1.0 + e);
    }
    return v;
}
