#include "io/block_cache.hpp"

#include <algorithm>
#include <future>
#include <gdal_priv.h>
#include <list>
#include <map>
#include <mutex>
#include <vector>

#include "io/errors.hpp"

namespace lodforge {

namespace {

// A decoded block in the band's native type: rows of `stride` values (a whole native block read
// with ReadBlock is stored at its full size, partial blocks at the raster's edge included).
struct Block {
  std::vector<unsigned char> bytes;
  int stride = 0;
};

struct Key {
  std::string path;
  int band, bx, by;
  auto operator<=>(const Key&) const = default;
};

// The blocks a band is cut into: its own when they hold at most 4 MB, whole strips grouped to
// about 1 MB (a strip is as wide as the raster: cutting it would decode it once per piece), and
// 512-pixel squares of larger blocks (a whole-image block; GDAL's cache holds it meanwhile).
cv::Size block_grid(GDALRasterBand& band, cv::Size raster) {
  int bw = 0, bh = 0;
  band.GetBlockSize(&bw, &bh);
  bw = std::clamp(bw, 1, raster.width);
  bh = std::clamp(bh, 1, raster.height);
  const std::size_t pixel = std::max(1, GDALGetDataTypeSizeBytes(band.GetRasterDataType()));
  const std::size_t bytes = std::size_t(bw) * bh * pixel;
  if (bw == raster.width && bh < raster.height) {  // strips
    const std::size_t group = std::max<std::size_t>(1, (std::size_t(1) << 20) / bytes);
    return {bw, int(std::min<std::size_t>(std::size_t(bh) * group, raster.height))};
  }
  if (bytes <= (std::size_t(4) << 20)) return {bw, bh};
  return {std::min(bw, 512), std::min(bh, 512)};
}

void read_direct(GDALRasterBand& band, const std::string& path, int band_index, GDALDataType type, const cv::Rect& w, void* out) {
  if (band.RasterIO(GF_Read, w.x, w.y, w.width, w.height, out, w.width, w.height, type, 0, 0) != CE_None)
    throw InputError("'" + path + "': cannot read band " + std::to_string(band_index) + ": " + CPLGetLastErrorMsg());
}

}  // namespace

struct BlockCache::Impl {
  struct Entry {
    std::shared_future<std::shared_ptr<const Block>> block;
    std::size_t bytes = 0;  // 0 while being decoded (never evicted then)
    std::list<Key>::iterator recent;
    cv::Rect rect;  // pixels of the raster it covers
  };
  std::size_t budget;
  std::size_t used = 0, decoded = 0;
  mutable std::mutex mutex;
  std::map<Key, Entry> entries;
  std::list<Key> recency;  // most recently used first

  void evict() {  // with the mutex held
    for (auto k = recency.end(); used > budget && k != recency.begin();) {
      --k;
      auto e = entries.find(*k);
      if (e == entries.end()) {  // its entry could not be made
        k = recency.erase(k);
        continue;
      }
      if (e->second.bytes == 0) continue;
      used -= e->second.bytes;
      entries.erase(e);
      k = recency.erase(k);
    }
  }

  // native: rect is one of the band's own blocks (bx, by), read with ReadBlock: straight from the
  // driver into the block, not through GDAL's block cache (which would hold a second copy).
  std::shared_ptr<const Block> get(GDALRasterBand& band, const std::string& path, const Key& key, const cv::Rect& rect,
                                   bool native) {
    std::unique_lock lock(mutex);
    if (auto found = entries.find(key); found != entries.end()) {
      recency.splice(recency.begin(), recency, found->second.recent);
      std::shared_future<std::shared_ptr<const Block>> block = found->second.block;
      lock.unlock();
      return block.get();  // waits while another thread decodes it; rethrows its error
    }
    std::promise<std::shared_ptr<const Block>> promise;
    recency.push_front(key);  // first, so that a failure here leaves no entry without its node
    Entry& entry = entries[key];
    entry.block = promise.get_future().share();
    entry.recent = recency.begin();
    entry.rect = rect;
    lock.unlock();

    std::shared_ptr<Block> block;
    try {
      const GDALDataType type = band.GetRasterDataType();
      const int value_bytes = GDALGetDataTypeSizeBytes(type);
      block = std::make_shared<Block>();
      if (native) {
        int bw = 0, bh = 0;
        band.GetBlockSize(&bw, &bh);
        block->bytes.resize(std::size_t(bw) * bh * value_bytes);
        block->stride = bw;
        if (band.ReadBlock(key.bx, key.by, block->bytes.data()) != CE_None)
          throw InputError("'" + path + "': cannot read band " + std::to_string(key.band) + ": " + CPLGetLastErrorMsg());
      } else {
        block->bytes.resize(std::size_t(rect.area()) * value_bytes);
        block->stride = rect.width;
        read_direct(band, path, key.band, type, rect, block->bytes.data());
      }
    } catch (...) {  // no entry stays behind: the waiters get the error, a later read tries again
      lock.lock();
      recency.erase(entry.recent);
      entries.erase(key);
      lock.unlock();
      promise.set_exception(std::current_exception());
      throw;
    }
    promise.set_value(block);
    lock.lock();
    entry.bytes = std::max<std::size_t>(block->bytes.size(), 1);
    used += entry.bytes;
    ++decoded;
    evict();
    return block;
  }
};

BlockCache::BlockCache(std::size_t budget_bytes) : impl_(std::make_unique<Impl>()) { impl_->budget = budget_bytes; }
BlockCache::~BlockCache() = default;

void BlockCache::read(GDALDataset& dataset, const std::string& path, int band_index, int type, const cv::Rect& w, void* out) {
  GDALRasterBand* band = dataset.GetRasterBand(band_index);
  if (!band) throw InputError("'" + path + "': has no band " + std::to_string(band_index));
  const cv::Rect bounds(0, 0, dataset.GetRasterXSize(), dataset.GetRasterYSize());
  const auto out_type = static_cast<GDALDataType>(type);
  if ((w & bounds) != w || w.empty()) return read_direct(*band, path, band_index, out_type, w, out);  // GDAL's own answer, error included
  const cv::Size grid = block_grid(*band, bounds.size());
  int native_w = 0, native_h = 0;
  band->GetBlockSize(&native_w, &native_h);
  const bool whole_blocks = grid == cv::Size(native_w, native_h);
  const GDALDataType native = band->GetRasterDataType();
  const int in_size = GDALGetDataTypeSizeBytes(native), out_size = GDALGetDataTypeSizeBytes(out_type);
  for (int by = w.y / grid.height; by <= (w.y + w.height - 1) / grid.height; ++by)
    for (int bx = w.x / grid.width; bx <= (w.x + w.width - 1) / grid.width; ++bx) {
      const cv::Rect rect = cv::Rect(bx * grid.width, by * grid.height, grid.width, grid.height) & bounds;
      const std::shared_ptr<const Block> block = impl_->get(*band, path, Key{path, band_index, bx, by}, rect, whole_blocks);
      const cv::Rect part = rect & w;
      for (int y = part.y; y < part.y + part.height; ++y) {
        const unsigned char* from = block->bytes.data() + (std::size_t(y - rect.y) * block->stride + (part.x - rect.x)) * in_size;
        auto* to = static_cast<unsigned char*>(out) + (std::size_t(y - w.y) * w.width + (part.x - w.x)) * out_size;
        // The conversion RasterIO itself applies, so the values are the same as a direct read.
        GDALCopyWords64(from, native, in_size, to, out_type, out_size, part.width);
      }
    }
}

void read_window(BlockCache* cache, GDALDataset& dataset, const std::string& path, int band, int type, const cv::Rect& w,
                 void* out) {
  if (cache) return cache->read(dataset, path, band, type, w, out);
  GDALRasterBand* b = dataset.GetRasterBand(band);
  if (!b) throw InputError("'" + path + "': has no band " + std::to_string(band));
  read_direct(*b, path, band, static_cast<GDALDataType>(type), w, out);
}

void BlockCache::keep_only(const std::vector<cv::Rect>& needed) {
  std::lock_guard lock(impl_->mutex);
  for (auto e = impl_->entries.begin(); e != impl_->entries.end();) {
    const bool keep = e->second.bytes == 0 ||
                      std::any_of(needed.begin(), needed.end(), [&](const cv::Rect& r) { return (r & e->second.rect).area() > 0; });
    if (keep) { ++e; continue; }
    impl_->used -= e->second.bytes;
    impl_->recency.erase(e->second.recent);
    e = impl_->entries.erase(e);
  }
}

std::size_t BlockCache::held_bytes() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->used;
}

std::size_t BlockCache::decoded_blocks() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->decoded;
}

}  // namespace lodforge
