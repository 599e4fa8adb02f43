// The I/O floor of a run (issue 7): a program that does nothing but read every pixel of the given
// rasters with GDAL, block row by block row in each band's native type, as a run's readers must.
// bench/performance.sh times the whole process (start-up and loading GDAL included, as in a
// run's wall time); the program prints the seconds of the reads alone.
//   usage: io_floor RASTER [RASTER...]
#include <gdal_priv.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <vector>

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: io_floor RASTER [RASTER...]\n");
    return 2;
  }
  GDALAllRegister();
  GDALSetCacheMax64(std::int64_t(64) << 20);  // as a run's default (tiling.gdal_cache_mb): blocks pass through, none is read twice
  const auto start = std::chrono::steady_clock::now();
  std::vector<unsigned char> buffer;
  for (int a = 1; a < argc; ++a) {
    GDALDataset* d = static_cast<GDALDataset*>(GDALOpen(argv[a], GA_ReadOnly));
    if (!d) {
      std::fprintf(stderr, "io_floor: cannot open '%s'\n", argv[a]);
      return 1;
    }
    for (int b = 1; b <= d->GetRasterCount(); ++b) {
      GDALRasterBand* band = d->GetRasterBand(b);
      int block_x = 0, block_y = 0;
      band->GetBlockSize(&block_x, &block_y);
      const GDALDataType type = band->GetRasterDataType();
      const int bytes = GDALGetDataTypeSizeBytes(type), width = d->GetRasterXSize(), height = d->GetRasterYSize();
      buffer.resize(std::size_t(width) * block_y * bytes);
      for (int y = 0; y < height; y += block_y) {
        const int rows = std::min(block_y, height - y);
        if (band->RasterIO(GF_Read, 0, y, width, rows, buffer.data(), width, rows, type, 0, 0) != CE_None) {
          std::fprintf(stderr, "io_floor: reading '%s' failed\n", argv[a]);
          return 1;
        }
      }
    }
    GDALClose(d);
  }
  std::printf("%.4f\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return 0;
}
