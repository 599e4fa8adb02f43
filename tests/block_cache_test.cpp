#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <gdal_priv.h>
#include <random>
#include <thread>
#include <vector>

#include "io/block_cache.hpp"
#include "io/errors.hpp"
#include "support/process.hpp"

namespace fs = std::filesystem;

namespace lodforge {
namespace {

struct Dataset {
  explicit Dataset(const std::string& path) : d(static_cast<GDALDataset*>(GDALOpen(path.c_str(), GA_ReadOnly))) {}
  ~Dataset() { GDALClose(d); }
  GDALDataset* d;
};

class BlockCacheTest : public ::testing::Test {
 protected:
  void SetUp() override {
    GDALAllRegister();
    dir = test::fresh_test_directory("lodforge_block_cache");
    // 300 x 200 Float32, tiled in 64 x 64 blocks (5 x 4 of them, the last ones partial), deflated.
    path = (dir / "tiled.tif").string();
    char** options = CSLSetNameValue(nullptr, "TILED", "YES");
    options = CSLSetNameValue(options, "BLOCKXSIZE", "64");
    options = CSLSetNameValue(options, "BLOCKYSIZE", "64");
    options = CSLSetNameValue(options, "COMPRESS", "DEFLATE");
    GDALDataset* d = GetGDALDriverManager()->GetDriverByName("GTiff")->Create(path.c_str(), 300, 200, 1, GDT_Float32, options);
    CSLDestroy(options);
    std::vector<float> values(300 * 200);
    std::mt19937 random(7);
    for (float& v : values) v = std::uniform_real_distribution<float>(-50, 400)(random);
    EXPECT_EQ(d->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, 300, 200, values.data(), 300, 200, GDT_Float32, 0, 0), CE_None);
    GDALClose(d);
  }

  template <class T>
  std::vector<T> direct(const cv::Rect& w, GDALDataType type) {
    Dataset d(path);
    std::vector<T> out(w.area());
    EXPECT_EQ(d.d->GetRasterBand(1)->RasterIO(GF_Read, w.x, w.y, w.width, w.height, out.data(), w.width, w.height, type, 0, 0), CE_None);
    return out;
  }

  fs::path dir;
  std::string path;
};

TEST_F(BlockCacheTest, WindowsEqualDirectReadsAndEachBlockIsDecodedOnce) {
  BlockCache cache(64 << 20);
  Dataset d(path);
  const std::vector<cv::Rect> windows = {{0, 0, 300, 200}, {10, 20, 70, 90}, {63, 63, 2, 2}, {250, 150, 50, 50}, {128, 0, 1, 200}};
  for (const cv::Rect& w : windows) {
    std::vector<float> f(w.area());
    cache.read(*d.d, path, 1, GDT_Float32, w, f.data());
    EXPECT_EQ(f, direct<float>(w, GDT_Float32)) << w.x << "," << w.y << " " << w.width << "x" << w.height;
    std::vector<std::int32_t> i(w.area());  // converted as RasterIO converts
    cache.read(*d.d, path, 1, GDT_Int32, w, i.data());
    EXPECT_EQ(i, direct<std::int32_t>(w, GDT_Int32)) << w.x << "," << w.y << " " << w.width << "x" << w.height;
  }
  EXPECT_EQ(cache.decoded_blocks(), 5u * 4u);  // the first window touched them all; the rest were hits
}

TEST_F(BlockCacheTest, KeepOnlyFreesTheBlocksNoNeededWindowOverlaps) {
  BlockCache cache(64 << 20);
  Dataset d(path);
  std::vector<float> all(300 * 200);
  cache.read(*d.d, path, 1, GDT_Float32, {0, 0, 300, 200}, all.data());
  ASSERT_EQ(cache.decoded_blocks(), 20u);
  const std::size_t block = 64 * 64 * sizeof(float);
  // Keep what a window over blocks (1..2, 1) needs: 2 full blocks stay, 18 are freed.
  cache.keep_only({{70, 70, 60, 10}});
  EXPECT_EQ(cache.held_bytes(), 2 * block);
  std::vector<float> w(60 * 10);
  cache.read(*d.d, path, 1, GDT_Float32, {70, 70, 60, 10}, w.data());
  EXPECT_EQ(cache.decoded_blocks(), 20u);  // still cached
  EXPECT_EQ(w, direct<float>({70, 70, 60, 10}, GDT_Float32));
  // A freed block read again is decoded again, with the same values.
  std::vector<float> corner(5 * 5);
  cache.read(*d.d, path, 1, GDT_Float32, {0, 0, 5, 5}, corner.data());
  EXPECT_EQ(cache.decoded_blocks(), 21u);
  EXPECT_EQ(corner, direct<float>({0, 0, 5, 5}, GDT_Float32));
  cache.keep_only({});
  EXPECT_EQ(cache.held_bytes(), 0u);
}

TEST_F(BlockCacheTest, ThreadsShareBlocksAndASmallBudgetStaysCorrect) {
  for (const std::size_t budget : {std::size_t(64) << 20, std::size_t(20000)}) {  // all blocks, or ~1 block
    BlockCache cache(budget);
    std::atomic<int> mismatches{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
      threads.emplace_back([&, t] {
        Dataset d(path);  // each thread its own handle, as the run's readers
        std::mt19937 random(t);
        for (int k = 0; k < 40; ++k) {
          const int x = std::uniform_int_distribution<int>(0, 299)(random), y = std::uniform_int_distribution<int>(0, 199)(random);
          const cv::Rect w(x, y, std::uniform_int_distribution<int>(1, 300 - x)(random), std::uniform_int_distribution<int>(1, 200 - y)(random));
          std::vector<float> f(w.area());
          cache.read(*d.d, path, 1, GDT_Float32, w, f.data());
          if (f != direct<float>(w, GDT_Float32)) ++mismatches;
        }
      });
    for (std::thread& t : threads) t.join();
    EXPECT_EQ(mismatches.load(), 0) << "budget " << budget;
    if (budget > 1000000) EXPECT_LE(cache.decoded_blocks(), 20u);  // never twice, whatever the thread
    else EXPECT_GT(cache.decoded_blocks(), 20u);                    // evicted and decoded again
  }
}

TEST_F(BlockCacheTest, StripsAreReadWholeAndGrouped) {
  // The same values in 3-row strips (an untiled GeoTIFF): cached as whole-width groups of strips.
  const std::string strips = (dir / "strips.tif").string();
  char** options = CSLSetNameValue(nullptr, "BLOCKYSIZE", "3");
  GDALDataset* source = static_cast<GDALDataset*>(GDALOpen(path.c_str(), GA_ReadOnly));
  GDALClose(GetGDALDriverManager()->GetDriverByName("GTiff")->CreateCopy(strips.c_str(), source, FALSE, options, nullptr, nullptr));
  GDALClose(source);
  CSLDestroy(options);
  Dataset d(strips);
  int bw = 0, bh = 0;
  d.d->GetRasterBand(1)->GetBlockSize(&bw, &bh);
  ASSERT_EQ(bw, 300);
  ASSERT_EQ(bh, 3);
  BlockCache cache(64 << 20);
  for (const cv::Rect& w : {cv::Rect(0, 0, 300, 200), cv::Rect(17, 101, 40, 60), cv::Rect(299, 199, 1, 1)}) {
    std::vector<float> f(w.area());
    cache.read(*d.d, strips, 1, GDT_Float32, w, f.data());
    EXPECT_EQ(f, direct<float>(w, GDT_Float32)) << w.x << "," << w.y;
  }
  // 1 MB groups of 3.6 KB strips: 291 strips, i.e. the 67 strips of the raster in one block.
  EXPECT_EQ(cache.decoded_blocks(), 1u);
}

TEST_F(BlockCacheTest, AWindowOutsideTheRasterIsAnErrorNamingTheFile) {
  BlockCache cache(1 << 20);
  Dataset d(path);
  std::vector<float> f(100);
  try {
    cache.read(*d.d, path, 1, GDT_Float32, cv::Rect(295, 195, 10, 10), f.data());
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tiled.tif': cannot read band 1"), std::string::npos) << e.what();
  }
  try {
    cache.read(*d.d, path, 2, GDT_Float32, cv::Rect(0, 0, 10, 10), f.data());
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tiled.tif': has no band 2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lodforge
