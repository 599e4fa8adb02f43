// Decoded raster blocks shared by all the threads of a run. GDAL's block cache belongs to an open
// dataset, and a dataset handle serves one thread at a time, so threads with their own handles
// decode the blocks their tiles share (tiles overlap by their halo) once each. Here a block is
// decoded once, by the first thread that needs it (the others wait for it), and kept in its
// native type while the byte budget allows, least recently used first out.
#pragma once
#include <cstddef>
#include <memory>
#include <opencv2/core/types.hpp>
#include <string>
#include <vector>

class GDALDataset;

namespace lodforge {

class BlockCache {
 public:
  explicit BlockCache(std::size_t budget_bytes);
  ~BlockCache();
  BlockCache(const BlockCache&) = delete;
  BlockCache& operator=(const BlockCache&) = delete;

  // Reads window w of band `band` (1-based) of the raster at path, through dataset (the calling
  // thread's own handle on it), converted to GDAL data type `type` (a GDALDataType) into out:
  // w.height rows of w.width values, contiguous. Throws InputError naming path when GDAL cannot.
  void read(GDALDataset& dataset, const std::string& path, int band, int type, const cv::Rect& w, void* out);

  // Drops every decoded block that overlaps none of `needed` (pixel rectangles, one grid for all
  // the rasters read through the cache): a run that knows which windows come next frees the
  // blocks no later tile reads instead of holding them until the budget is full. A dropped
  // block that is read again after all is decoded again; blocks being decoded stay.
  void keep_only(const std::vector<cv::Rect>& needed);

  // Blocks decoded so far (each decode counted once, whichever thread made it), and the bytes
  // held now.
  std::size_t decoded_blocks() const;
  std::size_t held_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Window w of a band as `type` through cache, or straight from GDAL when cache is null: the same
// values and the same errors either way.
void read_window(BlockCache* cache, GDALDataset& dataset, const std::string& path, int band, int type, const cv::Rect& w,
                 void* out);

}  // namespace lodforge
