#pragma once
// vtloc-soak's picture: host RSS and GPU memory over the runs.
#include <string>
#include <vector>

namespace vtloc::bench {

// Two panels (RSS, GPU memory; MiB against the run index), the warm-up
// shaded, RSS's fitted line after it drawn. Written atomically; throws
// vtloc::Error naming the path when it cannot be.
void plot_soak(const std::string& path, const std::vector<double>& rss_mib, const std::vector<double>& gpu_mib,
               size_t warmup_runs, double rss_slope_per_run);

}  // namespace vtloc::bench
