// Progress of a long run: a bar on a terminal, JSON lines otherwise (for logs and schedulers).
#pragma once
#include <chrono>
#include <cstddef>

namespace lodforge {

class Progress {
 public:
  Progress(std::size_t tiles_total, bool terminal);
  void update(std::size_t tiles_done, std::size_t buildings_done);
  void finish();

 private:
  std::size_t total_;
  bool terminal_;
  std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace lodforge
