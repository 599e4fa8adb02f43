#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/core.hpp>
#include <set>

#include "geometry/polygon.hpp"
#include "support/process.hpp"
#include "synth/city.hpp"

namespace lodforge {
namespace {

TEST(Synth, SameSeedSameCity) {
  SynthOptions o;
  o.width_m = o.height_m = 150;
  const SynthCity a = generate_city(o), b = generate_city(o);
  ASSERT_EQ(a.buildings.size(), b.buildings.size());
  EXPECT_EQ(cv::norm(a.building_mask, b.building_mask, cv::NORM_L1), 0.0);
  EXPECT_EQ(cv::norm(a.dsm, b.dsm, cv::NORM_L1), 0.0);
  o.seed = 2;
  EXPECT_GT(cv::norm(a.building_mask, generate_city(o).building_mask, cv::NORM_L1), 0.0);
}

// The files too: lodforge synth and regularize write the same bytes twice (their GeoPackages'
// last change is the run's, not the clock's).
TEST(Synth, TheCommandsWriteTheSameBytesTwice) {
  const std::filesystem::path dir = test::fresh_test_directory("synth_bytes");
  for (const char* name : {"a", "b"}) {
    const test::CommandOutput synth = test::lodforge("synth --out " + (dir / name).string() + " --size-m 100 --seed 4");
    ASSERT_EQ(synth.code, 0) << synth.output;
    const test::CommandOutput lod0 = test::lodforge("regularize --mask " + (dir / name / "seg_class.tif").string() + " --building-value 6 --out " +
                                                    (dir / name / "lod0.gpkg").string() + " -j 1");
    ASSERT_EQ(lod0.code, 0) << lod0.output;
  }
  for (const char* file : {"footprints.gpkg", "seg_class.tif", "dsm.tif", "lod0.gpkg"})
    EXPECT_EQ(test::slurp(dir / "a" / file), test::slurp(dir / "b" / file)) << file;
}

// The degradation in metres is the same physical noise at every pixel size: the area between the
// degraded mask and the truth, per metre of true boundary, is the mean displacement of the
// boundary, about 0.8 of its RMS (0.5 m amplitude: RMS 0.35 m, mean about 0.28 m).
TEST(Synth, AWobbleInMetresIsTheSameAtEveryPixelSize) {
  std::vector<double> displacement;
  for (const double pixel : {0.2, 0.5}) {
    SynthOptions o;
    o.width_m = o.height_m = 200;
    o.pixel_size_m = pixel;
    o.boundary_noise_m = 0.5;
    o.noise_wavelength_m = 8;
    o.corner_radius_m = 0;
    o.speckle_per_km2 = 0;
    const SynthCity city = generate_city(o);
    cv::Mat truth = cv::Mat::zeros(city.building_mask.size(), CV_8U);
    double boundary = 0;
    for (const SynthBuilding& b : city.buildings) {
      rasterize(truth, b.footprint, city.transform);
      boundary += perimeter(b.footprint.outer);
      for (const Ring& h : b.footprint.holes) boundary += perimeter(h);
    }
    const double differing_m2 = cv::countNonZero(truth ^ city.building_mask) * pixel * pixel;
    displacement.push_back(differing_m2 / boundary);
    EXPECT_GT(displacement.back(), 0.18) << pixel;
    EXPECT_LT(displacement.back(), 0.40) << pixel;
  }
  EXPECT_NEAR(displacement[0], displacement[1], 0.3 * displacement[0]);
}

// A network's smoothing (blur_m): along a straight wall the boundary stays where it is (the
// blurred step crosses its level there), a convex corner is cut and a concave one filled along
// about a blur, and a bias moves every wall out by itself (with a blur, by four blurs at most). An
// L of 20 m x 20 m less a 10 m x 10 m quarter at 0.1 m pixels, blurred by 1 m.
TEST(Synth, ANetworksBlurCutsCornersKeepsWallsAndABiasMovesThem) {
  const double pixel = 0.1, blur = 1.0;
  cv::Mat truth = cv::Mat::zeros(400, 400, CV_8U);
  truth(cv::Rect(100, 100, 200, 200)).setTo(1);
  truth(cv::Rect(200, 100, 100, 100)).setTo(0);  // (the upper right quarter: a concave corner at 200, 200)
  const auto width_at_row = [](const cv::Mat& m, int row) { return cv::countNonZero(m.row(row)); };
  const auto degraded = [&](double bias_m, double blur_m) {
    return degrade_mask(truth, 0, 0, 1, 3.0, true, blur_m / pixel, bias_m / pixel);
  };
  const cv::Mat blurred = degraded(0, blur);
  // The walls in place: the lower half's rows 20 m wide (the corners a few blurs away).
  EXPECT_NEAR(width_at_row(blurred, 250), 200, 1);
  // The convex corner at (100, 300) cut: on its diagonal the boundary is where Phi(d / blur)^2 =
  // 1/2, d = 0.545 blur from each wall (5.45 px); the concave corner at (200, 200) filled alike.
  EXPECT_EQ(blurred.at<uint8_t>(296, 103), 0);   // 3.5 px in from each wall: cut
  EXPECT_EQ(blurred.at<uint8_t>(292, 107), 1);   // 7.5 px in: kept
  EXPECT_EQ(truth.at<uint8_t>(197, 203), 0);
  EXPECT_EQ(blurred.at<uint8_t>(197, 203), 1);   // 3.5 px out of the concave corner: filled
  EXPECT_EQ(blurred.at<uint8_t>(193, 207), 0);   // 7.5 px out: not
  // A bias of 0.5 m moves both walls out by 5 px, blurred or not; -0.5 m in.
  EXPECT_NEAR(width_at_row(degraded(0.5, blur), 250), 210, 1);
  EXPECT_NEAR(width_at_row(degraded(0.5, 0), 250), 210, 1);
  EXPECT_NEAR(width_at_row(degraded(-0.5, 0), 250), 190, 1);
  // A bias of many blurs is taken as four: the walls 4 m in, the row still one run (no pixel lost
  // inside to the blur's rounding).
  const cv::Mat eroded = degraded(-8.0, blur);
  EXPECT_NEAR(width_at_row(eroded, 250), 120, 2);
  std::vector<cv::Point> set;
  cv::findNonZero(eroded.row(250), set);
  ASSERT_FALSE(set.empty());
  EXPECT_EQ(set.back().x - set.front().x + 1, width_at_row(eroded, 250));
}

TEST(Synth, CityHasEveryKindValidFootprintsAndRoofsAboveGround) {
  SynthOptions o;
  o.width_m = o.height_m = 500;
  const SynthCity city = generate_city(o);
  std::set<std::string> kinds;
  for (const SynthBuilding& b : city.buildings) {
    kinds.insert(b.kind);
    EXPECT_EQ(polygon_problem(b.footprint), "") << b.kind;
    EXPECT_GT(b.roof_height - b.ground_height, 4.9);
  }
  for (const char* k : {"rectangle", "l_shape", "t_shape", "u_shape", "cut45", "courtyard", "row_house", "round", "irregular"})
    EXPECT_TRUE(kinds.count(k)) << k;
  // The degraded mask stays close to the truth but is not identical.
  cv::Mat truth = cv::Mat::zeros(city.building_mask.size(), CV_8U);
  for (const SynthBuilding& b : city.buildings) rasterize(truth, b.footprint, city.transform);
  const double both = cv::countNonZero(truth & city.building_mask);
  const double either = cv::countNonZero(truth | city.building_mask);
  EXPECT_GT(both / either, 0.9);
  EXPECT_LT(both / either, 0.995);
}

}  // namespace
}  // namespace lodforge
