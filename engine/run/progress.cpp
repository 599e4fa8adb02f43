#include "run/progress.hpp"

#include <cstdio>
#include <string>

namespace lodforge {

Progress::Progress(std::size_t tiles_total, Mode mode)
    : total_(tiles_total), mode_(mode), start_(std::chrono::steady_clock::now()), last_(start_) {}

void Progress::update(std::size_t done, std::size_t buildings) {
  if (mode_ == Mode::none) return;
  const bool terminal_ = mode_ == Mode::bar;
  const auto now = std::chrono::steady_clock::now();
  if (done < total_ && now - last_ < std::chrono::milliseconds(terminal_ ? 200 : 2000)) return;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double rate = elapsed > 0 ? buildings / elapsed : 0;
  const double eta = done > 0 ? elapsed * double(total_ - done) / double(done) : 0;
  if (terminal_) {
    const int width = 30;
    const int filled = total_ ? int(width * done / total_) : width;
    std::fprintf(stderr, "\r[%s%s] %zu/%zu tiles, %zu buildings, %.1f buildings/s, ETA %.0f s   ",
                 std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(), done, total_, buildings,
                 rate, eta);
  } else {
    std::fprintf(stderr, "{\"progress\": {\"tiles_done\": %zu, \"tiles_total\": %zu, \"buildings\": %zu, "
                 "\"buildings_per_s\": %.2f, \"eta_s\": %.1f}}\n", done, total_, buildings, rate, eta);
  }
  std::fflush(stderr);
}

void Progress::finish() {
  if (mode_ == Mode::bar) std::fprintf(stderr, "\n");
}

}  // namespace lodforge
