#include "io/atomic_file.hpp"

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

void write_text_atomically(const std::filesystem::path& path, const std::string& text) {
  AtomicTextFile file(path);
  file.out() << text;
  file.commit();
}

}  // namespace lodforge
