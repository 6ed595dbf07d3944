#include "engine/io/colormap.h"

#include <cmath>

namespace vtloc::io {

std::array<uint8_t, 3> heat_color(float t) {
    // Hand-picked anchors, evenly spaced in t; linear in sRGB between them.
    // Relative luminance of the anchors: 0.011 0.040 0.071 0.12 0.22 0.41 0.82.
    static const float kAnchors[7][3] = {{12, 22, 72},   {38, 44, 138},  {92, 50, 160}, {164, 52, 132},
                                         {222, 82, 78},  {247, 146, 42}, {252, 236, 120}};
    if (!(t > 0)) t = 0;  // also NaN
    if (t > 1) t = 1;
    float x = t * 6.0f;
    int i = int(x);
    if (i > 5) i = 5;
    float f = x - float(i);
    std::array<uint8_t, 3> c{};
    for (int k = 0; k < 3; ++k)
        c[size_t(k)] = uint8_t(std::lround(kAnchors[i][k] + f * (kAnchors[i + 1][k] - kAnchors[i][k])));
    return c;
}

}  // namespace vtloc::io
