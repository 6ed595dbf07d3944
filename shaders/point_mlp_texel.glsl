// The texel-buffer reads of point_mlp.comp, point_mlp_shfl.comp and
// point_mlp_ubo.comp: on lavapipe a texel fetch is a gather, a storage-buffer load
// with per-invocation addresses a loop over the lanes with a branch per lane.
layout(binding = 0) uniform samplerBuffer A;    // R32F
layout(binding = 1) uniform samplerBuffer A4;   // binding 0 again, RGBA32F
layout(binding = 6) uniform samplerBuffer C;    // R32F, MODE 1: the centres [S][3]
layout(binding = 7) uniform isamplerBuffer I;   // R32I, MODE 1 (and PAD): the ball indices [S][NS]
layout(binding = 8) uniform samplerBuffer F;    // R32F
layout(binding = 9) uniform samplerBuffer F4;   // binding 8 again, RGBA32F
layout(binding = 10) uniform samplerBuffer H4;  // RGBA32F, HIDDEN: W0 [CF + 3][K]
layout(binding = 11) uniform samplerBuffer HB4; // RGBA32F, HIDDEN: b0 [K]
#define LOAD_A(i) texelFetch(A, int(i)).x
#define LOAD_A4(i) texelFetch(A4, int(i))
#define LOAD_C(i) texelFetch(C, int(i)).x
#define LOAD_I(i) texelFetch(I, int(i)).x
#define LOAD_F(i) texelFetch(F, int(i)).x
#define LOAD_F4(i) texelFetch(F4, int(i))
#define LOAD_H4(i) texelFetch(H4, int(i))
#define LOAD_HB4(i) texelFetch(HB4, int(i))
