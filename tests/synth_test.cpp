#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <set>

#include "geometry/polygon.hpp"
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
