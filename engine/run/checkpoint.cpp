#include "run/checkpoint.hpp"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <cerrno>
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include "io/atomic_file.hpp"
#include "io/errors.hpp"

namespace lodforge {

namespace fs = std::filesystem;

namespace {

constexpr std::uint32_t kMagic = 0x4c4f4446;  // "LODF"
constexpr std::uint32_t kVersion = 6;  // 2: a checksum of the payload in the header; 3: each building's regularization seconds; 4: the heights' statistics; 5: each building's model; 6: the contours' cut (the raster's extent where its edge cuts them)

class Writer {
 public:
  template <class T>
  void pod(const T& v) { out_.write(reinterpret_cast<const char*>(&v), sizeof v); }
  void text(const std::string& s) { pod<std::uint64_t>(s.size()); out_.write(s.data(), std::streamsize(s.size())); }
  void ring(const Ring& r) {
    pod<std::uint64_t>(r.size());
    for (const Vec2& p : r) { pod(p.x()); pod(p.y()); }
  }
  void rings(const std::vector<Ring>& rs) {
    pod<std::uint64_t>(rs.size());
    for (const Ring& r : rs) ring(r);
  }
  std::string str() const { return out_.str(); }

 private:
  std::ostringstream out_;
};

class Reader {
 public:
  explicit Reader(std::string data) : data_(std::move(data)) {}
  template <class T>
  T pod() {
    T v{};
    if (pos_ + sizeof v > data_.size()) throw std::runtime_error("truncated");
    std::memcpy(&v, data_.data() + pos_, sizeof v);
    pos_ += sizeof v;
    return v;
  }
  std::uint64_t count() {
    const auto n = pod<std::uint64_t>();
    if (n > data_.size()) throw std::runtime_error("corrupt count");
    return n;
  }
  std::string text() {
    const auto n = count();
    if (pos_ + n > data_.size()) throw std::runtime_error("truncated");
    std::string s = data_.substr(pos_, n);
    pos_ += n;
    return s;
  }
  Ring ring() {
    Ring r(count());
    for (Vec2& p : r) { p.x() = pod<double>(); p.y() = pod<double>(); }
    return r;
  }
  std::vector<Ring> rings() {
    std::vector<Ring> rs(count());
    for (Ring& r : rs) r = ring();
    return rs;
  }
  bool at_end() const { return pos_ == data_.size(); }

 private:
  std::string data_;
  std::size_t pos_ = 0;
};

void write_atomically(const fs::path& path, const std::string& payload, std::uint64_t key) {
  Writer header;
  header.pod(kMagic);
  header.pod(kVersion);
  header.pod(key);
  header.pod<std::uint64_t>(payload.size());
  header.pod<std::uint64_t>(fnv1a(payload));
  const fs::path temp = path.string() + ".tmp-" + std::to_string(getpid());
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    out << header.str() << payload;
    out.flush();
    if (!out) {
      std::error_code ec;
      fs::remove(temp, ec);
      const std::string full = disk_full_note(path);
      throw InputError("'" + path.string() + "': cannot write checkpoint" + (full.empty() ? std::string(" (disk full or not writable?)") : full));
    }
  }
  fs::rename(temp, path);
}

// A file's layout is that of its version; a done or writing marker's (a text) has not changed since
// the checksum came (version 2): those an earlier build left are read, so that its files stay its
// own after an upgrade (an interrupted run's, which no tile index lists yet).
constexpr std::uint32_t kOldestMarkerVersion = 2;

// key: the expected key, or none to take any. oldest: the oldest version whose layout is this one's.
std::optional<Reader> read_checked(const fs::path& path, std::optional<std::uint64_t> key, std::uint32_t oldest = kVersion) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream buffer;
  buffer << in.rdbuf();
  const std::string data = buffer.str();
  // The header: magic, version, key, the payload's size and its checksum.
  std::uint32_t magic = 0, version = 0;
  std::uint64_t found = 0, size = 0, checksum = 0;
  constexpr std::size_t kHeader = sizeof magic + sizeof version + sizeof found + sizeof size + sizeof checksum;
  if (data.size() < kHeader) return std::nullopt;
  const char* at = data.data();
  for (const auto& [field, bytes] : {std::pair<void*, std::size_t>{&magic, sizeof magic}, {&version, sizeof version}, {&found, sizeof found},
                                     {&size, sizeof size}, {&checksum, sizeof checksum}}) {
    std::memcpy(field, at, bytes);
    at += bytes;
  }
  if (magic != kMagic || version < oldest || version > kVersion || (key && found != *key)) return std::nullopt;
  std::string rest = data.substr(kHeader);
  if (rest.size() != size || fnv1a(rest) != checksum) return std::nullopt;  // changed since written: recomputed
  return Reader(std::move(rest));
}

}  // namespace

std::string file_fingerprint(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return {};
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  std::uint64_t hash = fnv1a(std::string());
  std::uint64_t size = 0;
  std::vector<char> buffer(1 << 16);
  while (in.read(buffer.data(), std::streamsize(buffer.size())) || in.gcount() > 0) {
    hash = fnv1a(buffer.data(), std::size_t(in.gcount()), hash);
    size += std::uint64_t(in.gcount());
  }
  return std::to_string(size) + ":" + hex(hash);
}

TileOutputs summary_outputs(const std::string& summary) {
  TileOutputs out;
  std::istringstream in(summary);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("output\t", 0) != 0) continue;
    const std::size_t tab = line.find('\t', 7);
    if (tab == std::string::npos) continue;
    out.emplace_back(line.substr(7, tab - 7), line.substr(tab + 1));
  }
  return out;
}

std::string summary_output_line(const std::string& relative_path, const std::string& fingerprint) {
  return "output\t" + relative_path + "\t" + fingerprint + "\n";
}

std::string hex(std::uint64_t value) {
  char buffer[17];
  std::snprintf(buffer, sizeof buffer, "%016llx", static_cast<unsigned long long>(value));
  return buffer;
}

CheckpointStore::CheckpointStore(std::string directory) : directory_(std::move(directory)) {
  std::error_code ec;
  fs::create_directories(directory_, ec);
  if (ec || !fs::is_directory(directory_)) throw InputError("work_dir '" + directory_ + "': cannot create: " + ec.message());
  if (access(directory_.c_str(), W_OK) != 0) throw InputError("work_dir '" + directory_ + "': not writable");
}

std::string CheckpointStore::path(const std::string& stage, const std::string& tile) const {
  return (fs::path(directory_) / (tile + "." + stage)).string();
}

void CheckpointStore::save_contours(const std::string& tile, std::uint64_t key, const TileBuildings& t) const {
  Writer w;
  w.pod<std::int32_t>(t.dropped_small);
  w.pod<std::int32_t>(t.window.x);
  w.pod<std::int32_t>(t.window.y);
  w.pod<std::int32_t>(t.window.width);
  w.pod<std::int32_t>(t.window.height);
  w.pod<std::uint64_t>(t.too_large.size());
  for (const std::string& s : t.too_large) w.text(s);
  w.pod<std::uint64_t>(t.buildings.size());
  for (const BuildingContour& b : t.buildings) {
    w.pod<std::int32_t>(b.first_row);
    w.pod<std::int32_t>(b.first_col);
    w.pod<std::int64_t>(b.pixel_count);
    w.pod<std::int32_t>(b.bbox.x);
    w.pod<std::int32_t>(b.bbox.y);
    w.pod<std::int32_t>(b.bbox.width);
    w.pod<std::int32_t>(b.bbox.height);
    w.rings(b.rings);
    w.ring(b.cut);
  }
  write_atomically(path("contours", tile), w.str(), key);
}

std::optional<TileBuildings> CheckpointStore::load_contours(const std::string& tile, std::uint64_t key) const {
  auto r = read_checked(path("contours", tile), key);
  if (!r) return std::nullopt;
  try {
    TileBuildings t;
    t.dropped_small = r->pod<std::int32_t>();
    t.window.x = r->pod<std::int32_t>();
    t.window.y = r->pod<std::int32_t>();
    t.window.width = r->pod<std::int32_t>();
    t.window.height = r->pod<std::int32_t>();
    t.too_large.resize(r->count());
    for (std::string& s : t.too_large) s = r->text();
    t.buildings.resize(r->count());
    for (BuildingContour& b : t.buildings) {
      b.first_row = r->pod<std::int32_t>();
      b.first_col = r->pod<std::int32_t>();
      b.pixel_count = r->pod<std::int64_t>();
      b.bbox.x = r->pod<std::int32_t>();
      b.bbox.y = r->pod<std::int32_t>();
      b.bbox.width = r->pod<std::int32_t>();
      b.bbox.height = r->pod<std::int32_t>();
      b.rings = r->rings();
      b.cut = r->ring();
    }
    if (!r->at_end()) return std::nullopt;
    return t;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

void CheckpointStore::save_buildings(const std::string& tile, std::uint64_t key, const std::vector<BuildingOutput>& value) const {
  Writer w;
  w.pod<std::uint64_t>(value.size());
  for (const BuildingOutput& b : value) {
    w.pod(b.id);
    w.pod<std::int32_t>(b.first_row);
    w.pod<std::int32_t>(b.first_col);
    w.ring(b.footprint.outer);
    w.rings(b.footprint.holes);
    w.pod<std::uint8_t>(b.ok);
    w.text(b.stage);
    w.text(b.reason);
    w.text(b.model);
    w.pod<double>(b.seconds);  // (for the report's slowest buildings after a resumed run)
  }
  write_atomically(path("buildings", tile), w.str(), key);
}

std::optional<std::vector<BuildingOutput>> CheckpointStore::load_buildings(const std::string& tile, std::uint64_t key) const {
  auto r = read_checked(path("buildings", tile), key);
  if (!r) return std::nullopt;
  try {
    std::vector<BuildingOutput> value(r->count());
    for (BuildingOutput& b : value) {
      b.id = r->pod<std::int64_t>();
      b.first_row = r->pod<std::int32_t>();
      b.first_col = r->pod<std::int32_t>();
      b.footprint.outer = r->ring();
      b.footprint.holes = r->rings();
      b.ok = r->pod<std::uint8_t>() != 0;
      b.stage = r->text();
      b.reason = r->text();
      b.model = r->text();
      b.seconds = r->pod<double>();
    }
    if (!r->at_end()) return std::nullopt;
    return value;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

void CheckpointStore::save_blob(const std::string& stage, const std::string& tile, std::uint64_t key, const std::string& payload) const {
  Writer w;
  w.text(payload);
  write_atomically(path(stage, tile), w.str(), key);
}

std::optional<std::string> CheckpointStore::load_blob(const std::string& stage, const std::string& tile, std::uint64_t key) const {
  auto r = read_checked(path(stage, tile), key, stage == "writing" ? kOldestMarkerVersion : kVersion);
  if (!r) return std::nullopt;
  try {
    std::string payload = r->text();
    if (!r->at_end()) return std::nullopt;
    return payload;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

void CheckpointStore::mark_done(const std::string& tile, std::uint64_t key, const std::string& summary) const {
  Writer w;
  w.text(summary);
  write_atomically(path("done", tile), w.str(), key);
}

std::optional<std::string> CheckpointStore::last_done_summary(const std::string& tile) const {
  auto r = read_checked(path("done", tile), std::nullopt, kOldestMarkerVersion);
  if (!r) return std::nullopt;
  try {
    return r->text();
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

void CheckpointStore::record_intent(const std::string& tile, const std::vector<std::string>& relative_paths) const {
  std::string lines;
  for (const std::string& p : relative_paths) lines += p + "\n";
  save_blob("writing", tile, 0, lines);
}

std::set<std::string> CheckpointStore::own_files(const std::string& tile) const {
  std::set<std::string> files;
  if (auto last = last_done_summary(tile))
    for (const auto& output : summary_outputs(*last)) files.insert(output.first);
  if (auto intent = load_blob("writing", tile, 0)) {
    std::istringstream in(*intent);
    for (std::string line; std::getline(in, line);) if (!line.empty()) files.insert(line);
  }
  return files;
}

std::optional<std::string> CheckpointStore::done_summary(const std::string& tile, std::uint64_t key) const {
  auto r = read_checked(path("done", tile), key);
  if (!r) return std::nullopt;
  try {
    return r->text();
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

WorkDirLock::WorkDirLock(const std::string& directory, const std::string& name) {
  const std::string path = (fs::path(directory) / name).string();
  fd_ = open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) throw InputError("work_dir '" + directory + "': cannot create the lock file " + name + ": " + std::strerror(errno));
  if (flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    char buffer[32] = {};
    const ssize_t n = pread(fd_, buffer, sizeof buffer - 1, 0);
    close(fd_);
    fd_ = -1;
    const std::string pid = n > 0 ? std::string(buffer, std::size_t(n)) : "unknown";
    throw InputError("work_dir '" + directory + "': another lodforge run (pid " + pid.substr(0, pid.find('\n')) +
                     ") is using it; wait for it to end, or give this run another work_dir and output.dir");
  }
  const std::string pid = std::to_string(getpid()) + "\n";
  if (ftruncate(fd_, 0) != 0 || pwrite(fd_, pid.data(), pid.size(), 0) != ssize_t(pid.size())) {
    // The lock holds all the same; only the pid shown to a second run is missing.
  }
}

WorkDirLock::~WorkDirLock() {
  if (fd_ >= 0) close(fd_);  // releases the lock (the file stays: removing it would race a new holder)
}

}  // namespace lodforge
