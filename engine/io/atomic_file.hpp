// Text outputs that never look complete when they are not: written to PATH.partial-PID and
// renamed onto PATH by commit(); removed if never committed (an error, an exception). The PID
// lets concurrent processes (shards) tell their own temporary files from a dead one's.
#pragma once
#include <filesystem>
#include <fstream>
#include <string>

namespace lodforge {

class AtomicTextFile {
 public:
  explicit AtomicTextFile(std::filesystem::path path);  // throws InputError if it cannot create
  ~AtomicTextFile();
  AtomicTextFile(const AtomicTextFile&) = delete;
  AtomicTextFile& operator=(const AtomicTextFile&) = delete;
  std::ostream& out() { return out_; }
  void commit();  // flushes, checks, renames; throws InputError when writing failed (disk full?)

 private:
  std::filesystem::path path_, temp_;
  std::ofstream out_;
  bool done_ = false;
};

// When the file system holding path has (almost) no room left: "; the disk holding 'DIR' is full
// (N KB free)"; else empty. Appended to write errors, so that a full disk reads as one.
std::string disk_full_note(const std::filesystem::path& path);

// Removes the temporary files lodforge's writers leave when killed (NAME.tmp-PID..., NAME.partial-PID...,
// the PID followed by the end of the name or a dot) whose writer is gone: no process PID on this
// machine, and untouched for min_age_seconds (a writer on another machine sharing the directory
// holds its temporary file for seconds, not minutes). Returns how many.
int remove_stale_temporaries(const std::filesystem::path& directory, double min_age_seconds);

// The whole text at once.
void write_text_atomically(const std::filesystem::path& path, const std::string& text);

}  // namespace lodforge
