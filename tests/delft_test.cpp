// End to end on real data: Delft, AHN3 classification == 6 as the segmentation.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/core.hpp>

#include "eval/metrics.hpp"
#include "geometry/polygon.hpp"
#include "io/ogr_polygon.hpp"
#include "io/raster.hpp"
#include "pipeline/building.hpp"
#include "support/shapes.hpp"

namespace lodforge {
namespace {

std::string delft(const std::string& name) { return test::test_data() + "/delft-ahn3-bgt/derived/" + name; }

class Delft : public ::testing::TestWithParam<const char*> {};

TEST_P(Delft, EveryBuildingGetsAValidPolygonAndAStatus) {
  ASSERT_TRUE(std::filesystem::exists(delft("top_class_50cm.tif"))) << "shared data missing at " << test::test_data();
  const MaskRaster raster = read_building_mask(delft("top_class_50cm.tif"), BuildingSelector{});
  EXPECT_NEAR(raster.transform.pixel_size(), 0.5, 1e-12);
  const ContourResult contours = extract_contours(raster.mask, raster.transform, ContourOptions{});
  ASSERT_GT(contours.buildings.size(), 30u);
  CoreOptions options;
  options.corners.route = GetParam();
  int ok = 0;
  for (const BuildingContour& b : contours.buildings) {
    const BuildingResult r = regularize_building(b.rings, 0.5, options);
    EXPECT_EQ(polygon_problem(r.footprint), "") << "building at row " << b.first_row << " col " << b.first_col;
    EXPECT_GT(area(r.footprint), 0);
    EXPECT_TRUE(r.ok || (!r.failed_stage.empty() && !r.reason.empty()));
    ok += r.ok;
  }
  // Most buildings are regularized, not left to the fallback.
  EXPECT_GE(ok, int(0.85 * contours.buildings.size())) << ok << " of " << contours.buildings.size();
}

INSTANTIATE_TEST_SUITE_P(Routes, Delft, ::testing::Values("original", "deformed"));

// Against the BGT footprints (inside the area they cover): the regular outline's oblique walls,
// redrawn where the lattice outline explains them as well (models.stretch_fit_noise), make most
// corners square (0.55 with the redrawing off; the BGT's own share is 0.89), and the footprints
// are no worse for it in IoU or PoLiS.
TEST(DelftQuality, ObliqueCutsBecomeSquareCornersAtNoCost) {
  ASSERT_TRUE(std::filesystem::exists(delft("top_class_50cm.tif"))) << "shared data missing at " << test::test_data();
  const MaskRaster raster = read_building_mask(delft("top_class_50cm.tif"), BuildingSelector{});
  const ContourResult contours = extract_contours(raster.mask, raster.transform, ContourOptions{});
  const std::vector<PolygonWithHoles> truth = read_polygons(delft("bgt_pand_buildings.geojson"), "truth");
  const std::vector<PolygonWithHoles> aoi = read_polygons(delft("gt_coverage_aoi.geojson"), "aoi");
  ASSERT_EQ(aoi.size(), 1u);
  CoreOptions off;
  off.models.stretch_fit_noise = 0;
  std::vector<PolygonWithHoles> with, without;
  for (const BuildingContour& b : contours.buildings) {
    with.push_back(regularize_building(b.rings, 0.5, CoreOptions{}).footprint);
    without.push_back(regularize_building(b.rings, 0.5, off).footprint);
  }
  const EvalResult e = evaluate(with, truth, aoi.front()), e0 = evaluate(without, truth, aoi.front());
  EXPECT_GE(e.right_angle_share, 0.70) << "off: " << e0.right_angle_share;  // (0.739, off 0.547 measured)
  EXPECT_GE(e.right_angle_share, e0.right_angle_share + 0.10) << e.right_angle_share << " vs " << e0.right_angle_share;
  EXPECT_GE(e.overall_iou, e0.overall_iou - 0.001) << e.overall_iou << " vs " << e0.overall_iou;
  EXPECT_LE(e.polis, e0.polis + 0.005) << e.polis << " vs " << e0.polis;
  // (Square corners, not a staircase: a staircase scores 1 too.)
  EXPECT_LE(e.n_ratio, e0.n_ratio + 0.02) << e.n_ratio << " vs " << e0.n_ratio;
}

TEST(DelftRepair, SplitRunsThatMakeTheRingCrossAreRetriedUnsplit) {
  // A ragged tree blob at the raster's edge (first pixel row 387, col 9): with its runs split
  // at parallel offsets every repair attempt crosses itself; unsplit, one is valid.
  const MaskRaster raster = read_building_mask(delft("top_class_50cm.tif"), BuildingSelector{});
  const ContourResult contours = extract_contours(raster.mask, raster.transform, ContourOptions{});
  const BuildingContour* blob = nullptr;
  for (const BuildingContour& b : contours.buildings)
    if (b.first_row == 387 && b.first_col == 9) blob = &b;
  ASSERT_NE(blob, nullptr);
  const BuildingResult r = regularize_building(blob->rings, 0.5, CoreOptions{});
  EXPECT_TRUE(r.ok) << r.failed_stage << ": " << r.reason;
  EXPECT_EQ(polygon_problem(r.footprint), "");
}

TEST(DelftColours, IsprsColoursGiveTheSameMask) {
  const MaskRaster classes = read_building_mask(delft("top_class_50cm.tif"), BuildingSelector{});
  BuildingSelector blue;
  blue.rgb = std::array<int, 3>{0, 0, 255};
  const MaskRaster colours = read_building_mask(delft("top_class_isprs_colours_50cm.tif"), blue);
  EXPECT_EQ(cv::norm(classes.mask, colours.mask, cv::NORM_L1), 0.0);
}

}  // namespace
}  // namespace lodforge
