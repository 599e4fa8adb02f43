#include <gtest/gtest.h>

#include "commands/stage_options.hpp"
#include "io/errors.hpp"

namespace lodforge {
namespace {

TEST(Options, OverridesApplyByKeyPath) {
  StageOptions o;
  apply_overrides(o, {"labeling.kappa2=5", "corners.route=deformed", "contour.connectivity=4"});
  EXPECT_DOUBLE_EQ(o.core.labeling.kappa2, 5.0);
  EXPECT_EQ(o.core.corners.route, "deformed");
  EXPECT_EQ(o.contour.connectivity, 4);
}

TEST(Options, AllErrorsAreReportedTogetherWithTheirKeyPath) {
  StageOptions o;
  try {
    apply_overrides(o, {"labeling.kappa2=-1", "labeling.kappa3=1", "smoothing.passes=many", "corners.route=magic"});
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    const std::string text = e.what();
    EXPECT_NE(text.find("labeling.kappa2: must be >= 0"), std::string::npos) << text;
    EXPECT_NE(text.find("labeling.kappa3: unknown option"), std::string::npos) << text;
    EXPECT_NE(text.find("smoothing.passes: cannot read 'many'"), std::string::npos) << text;
    EXPECT_NE(text.find("corners.route: must be one of: original, deformed"), std::string::npos) << text;
  }
}

TEST(Options, DefaultsArePrintedWithHelp) {
  const std::string text = print_defaults();
  EXPECT_NE(text.find("labeling:\n"), std::string::npos);
  EXPECT_NE(text.find("  kappa2: 10  # label cost weight"), std::string::npos) << text;
  EXPECT_NE(text.find("  sigma_a_deg: 10  #"), std::string::npos);
}

}  // namespace
}  // namespace lodforge
