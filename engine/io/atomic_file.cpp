#include "io/atomic_file.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <sys/statvfs.h>
#include <unistd.h>

#include "io/errors.hpp"

namespace lodforge {

AtomicTextFile::AtomicTextFile(std::filesystem::path path)
    : path_(std::move(path)), temp_(path_.string() + ".partial-" + std::to_string(getpid())) {
  out_.open(temp_, std::ios::trunc);
  if (!out_) throw InputError("'" + path_.string() + "': cannot create" + disk_full_note(path_));
}

AtomicTextFile::~AtomicTextFile() {
  if (done_) return;
  out_.close();
  std::error_code ec;
  std::filesystem::remove(temp_, ec);
}

void AtomicTextFile::commit() {
  out_.flush();
  out_.close();
  if (!out_) {
    std::error_code ec;
    std::filesystem::remove(temp_, ec);
    done_ = true;
    const std::string full = disk_full_note(path_);
    throw InputError("'" + path_.string() + "': writing failed" + (full.empty() ? std::string(" (disk full or not writable?)") : full));
  }
  std::filesystem::rename(temp_, path_);
  done_ = true;
}

std::string disk_full_note(const std::filesystem::path& path) {
  std::filesystem::path dir = path.parent_path().empty() ? std::filesystem::path(".") : path.parent_path();
  struct statvfs st {};
  if (statvfs(dir.c_str(), &st) != 0) return {};
  const unsigned long long free_bytes = static_cast<unsigned long long>(st.f_bavail) * st.f_frsize;
  if (free_bytes >= 1024 * 1024) return {};
  return "; the disk holding '" + dir.string() + "' is full (" + std::to_string(free_bytes / 1024) + " KB free)";
}

int remove_stale_temporaries(const std::filesystem::path& directory, double min_age_seconds) {
  int removed = 0;
  std::error_code ec;
  const auto now = std::filesystem::file_time_type::clock::now();
  for (const auto& entry : std::filesystem::directory_iterator(directory, ec)) {
    const std::string name = entry.path().filename().string();
    std::size_t digits = std::string::npos;
    for (const char* marker : {".tmp-", ".partial-"})
      if (const std::size_t at = name.find(marker); at != std::string::npos) digits = at + std::strlen(marker);
    if (digits == std::string::npos) continue;
    const std::size_t end = std::min(name.find_first_not_of("0123456789", digits), name.size());
    if (end == digits || end - digits > 9 || (end < name.size() && name[end] != '.')) continue;  // not a pid
    const pid_t writer = pid_t(std::stol(name.substr(digits, end - digits)));
    if (writer == getpid() || kill(writer, 0) == 0 || errno != ESRCH) continue;  // at work (or not ours to judge)
    std::error_code time_error;
    const auto written = std::filesystem::last_write_time(entry.path(), time_error);
    if (time_error || std::chrono::duration<double>(now - written).count() < min_age_seconds) continue;
    if (std::filesystem::remove_all(entry.path(), time_error) > 0) ++removed;  // (a killed merge's staging directory too)
  }
  return removed;
}

void write_text_atomically(const std::filesystem::path& path, const std::string& text) {
  AtomicTextFile file(path);
  file.out() << text;
  file.commit();
}

}  // namespace lodforge
