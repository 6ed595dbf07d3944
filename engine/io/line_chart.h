#pragma once
// A small line chart as PNG (OpenCV drawing): `vtloc eval --sequence --plot`
// draws ND against the number of touches with it. Y starts at 0.
#include <string>
#include <vector>

namespace vtloc::io {

struct ChartSeries {
    std::string name;
    std::vector<double> y;  // one per x; NaN: no point
    bool dashed = false;
    int colour = -1;        // an index into the palette; -1: the series' own index
};

struct LineChart {
    std::string title, x_label, y_label;
    std::vector<double> x;
    std::vector<ChartSeries> series;
    int width = 1100, height = 600;
};

// Throws vtloc::Error naming `path` when there is nothing to draw or it cannot be written.
void save_line_chart_png(const std::string& path, const LineChart& chart);

}  // namespace vtloc::io
