#include "io/atomic_file.hpp"

#include <unistd.h>

#include "io/errors.hpp"

namespace lodforge {

AtomicTextFile::AtomicTextFile(std::filesystem::path path)
    : path_(std::move(path)), temp_(path_.string() + ".partial-" + std::to_string(getpid())) {
  out_.open(temp_, std::ios::trunc);
  if (!out_) throw InputError("'" + path_.string() + "': cannot create");
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
  if (!out_) throw InputError("'" + path_.string() + "': writing failed (disk full?)");
  std::filesystem::rename(temp_, path_);
  done_ = true;
}

void write_text_atomically(const std::filesystem::path& path, const std::string& text) {
  AtomicTextFile file(path);
  file.out() << text;
  file.commit();
}

}  // namespace lodforge
