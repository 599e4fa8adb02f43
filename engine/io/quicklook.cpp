#include "io/quicklook.hpp"

#include <cmath>
#include <filesystem>
#include <gdal_priv.h>
#include <opencv2/imgproc.hpp>
#include <unistd.h>

#include "io/errors.hpp"

namespace lodforge {

cv::Mat hillshade(const cv::Mat& dsm, const cv::Mat& valid, double pixel_size) {
  cv::Mat filled = dsm.clone();
  filled.setTo(0, valid == 0);
  cv::Mat dx, dy;
  cv::Sobel(filled, dx, CV_32F, 1, 0, 3, 1.0 / (8 * pixel_size));
  cv::Sobel(filled, dy, CV_32F, 0, 1, 3, 1.0 / (8 * pixel_size));
  const double zenith = M_PI / 4, azimuth = 7 * M_PI / 4;  // 45° high, from the north-west
  // cos(zenith) cos(slope) + sin(zenith) sin(slope) cos(azimuth - aspect), with slope and aspect
  // of the gradient g written out: (cos z + sin z (-gx cos az + gy sin az)) / sqrt(1 + |g|^2).
  const double cz = std::cos(zenith), sz = std::sin(zenith), ca = std::cos(azimuth), sa = std::sin(azimuth);
  cv::Mat shade(dsm.size(), CV_8U);
  for (int y = 0; y < dsm.rows; ++y) {
    const float* row_dx = dx.ptr<float>(y);
    const float* row_dy = dy.ptr<float>(y);
    const uint8_t* row_valid = valid.ptr<uint8_t>(y);
    uint8_t* out = shade.ptr<uint8_t>(y);
    for (int x = 0; x < dsm.cols; ++x) {
      const double gx = row_dx[x], gy = -row_dy[x];  // rows grow southwards
      const double v = (cz + sz * (-gx * ca + gy * sa)) / std::sqrt(1 + gx * gx + gy * gy);
      out[x] = row_valid[x] ? uint8_t(std::clamp(40 + 215 * v, 0.0, 255.0)) : 0;
    }
  }
  cv::Mat colour;
  cv::cvtColor(shade, colour, cv::COLOR_GRAY2BGR);
  return colour;
}

void write_quicklook(const std::string& path, cv::Mat image, const GeoTransform& t, const std::vector<QuicklookOutline>& outlines) {
  constexpr int shift = 3;
  auto draw = [&](const Ring& ring, const cv::Scalar& colour) {
    std::vector<cv::Point> points;
    for (const Vec2& p : ring) {
      const Vec2 q = t.to_pixel(p);
      points.emplace_back(int(std::lround(q.x() * (1 << shift))), int(std::lround(q.y() * (1 << shift))));
    }
    cv::polylines(image, std::vector<std::vector<cv::Point>>{points}, true, colour, 1, cv::LINE_AA, shift);
  };
  for (const QuicklookOutline& o : outlines) {
    const cv::Scalar colour = o.ok ? cv::Scalar(40, 40, 230) : cv::Scalar(0, 220, 255);  // BGR: red, yellow
    draw(o.footprint.outer, colour);
    for (const Ring& h : o.footprint.holes) draw(h, colour);
  }
  // Written by GDAL's PNG driver from an in-memory copy (bands in RGB order), with fast deflate:
  // a quick look is for the eye, and level 1 writes it several times faster.
  // (GDAL's drivers are registered once by main, before any worker thread.)
  const std::string temp = path + ".partial-" + std::to_string(getpid()) + ".png";
  GDALDriver* mem_driver = GetGDALDriverManager()->GetDriverByName("MEM");
  GDALDriver* png_driver = GetGDALDriverManager()->GetDriverByName("PNG");
  if (!mem_driver || !png_driver) throw InputError("'" + path + "': cannot write the quick-look image: GDAL has no MEM or PNG driver");
  CPLErrorReset();
  GDALDataset* memory = mem_driver->Create("", image.cols, image.rows, 3, GDT_Byte, nullptr);
  int bgr_to_rgb[3] = {3, 2, 1};
  bool ok = memory && memory->RasterIO(GF_Write, 0, 0, image.cols, image.rows, image.data, image.cols, image.rows, GDT_Byte, 3,
                                       bgr_to_rgb, 3, GSpacing(image.step), 1, nullptr) == CE_None;
  if (ok) {
    const char* options[] = {"ZLEVEL=1", nullptr};
    GDALDataset* png = png_driver->CreateCopy(temp.c_str(), memory, FALSE, const_cast<char**>(options), nullptr, nullptr);
    ok = png != nullptr;
    if (png) GDALClose(png);  // (the PNG driver writes the whole file in CreateCopy)
  }
  if (memory) GDALClose(memory);
  if (!ok) {
    const std::string error = CPLGetLastErrorMsg();
    std::error_code ignored;
    std::filesystem::remove(temp, ignored);
    throw InputError("'" + path + "': cannot write the quick-look image: " + error);
  }
  std::filesystem::rename(temp, path);
}

}  // namespace lodforge
