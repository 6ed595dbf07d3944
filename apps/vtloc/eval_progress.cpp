// vtloc eval: a progress bar on stderr, only on a terminal (tests and pipes
// see a clean stderr).
#include <cstdio>
#include <unistd.h>

#include "apps/vtloc/eval.h"

namespace vtloc::cli::eval {

Progress::Progress(std::string label, size_t total)
    : label_(std::move(label)), total_(total), tty_(isatty(fileno(stderr)) == 1) {
    draw();
}

Progress::~Progress() { finish(); }

void Progress::advance(size_t n) {
    done_ = std::min(total_, done_ + n);
    draw();
}

void Progress::finish() {
    if (finished_) return;
    finished_ = true;
    if (tty_) std::fprintf(stderr, "\r\033[K");  // leave no bar behind
}

void Progress::draw() {
    if (!tty_ || finished_) return;
    constexpr size_t kWidth = 30;
    const size_t filled = total_ ? done_ * kWidth / total_ : kWidth;
    std::string bar(filled, '#');
    bar.resize(kWidth, '.');
    std::fprintf(stderr, "\r%s [%s] %zu/%zu", label_.c_str(), bar.c_str(), done_, total_);
    std::fflush(stderr);
}

}  // namespace vtloc::cli::eval
