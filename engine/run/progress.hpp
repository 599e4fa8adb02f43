// Progress of a long run: a bar on a terminal, JSON lines otherwise (for logs and schedulers).
#pragma once
#include <chrono>
#include <cstddef>

namespace lodforge {

class Progress {
 public:
  enum class Mode { bar, json, none };
  Progress(std::size_t tiles_total, Mode mode);
  void update(std::size_t tiles_done, std::size_t buildings_done);
  void finish();

 private:
  std::size_t total_;
  Mode mode_;
  std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace lodforge
