#include "synth/city.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>
#include <Eigen/Geometry>

#include "geometry/polygon.hpp"

namespace lodforge {

namespace {

using Rng = std::mt19937_64;

double uniform(Rng& rng, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }

Ring rectangle(double w, double h) { return {{0, 0}, {w, 0}, {w, h}, {0, h}}; }

// Local shapes, counter-clockwise, in metres with the origin at a corner.
PolygonWithHoles make_shape(const std::string& kind, Rng& rng) {
  const double w = uniform(rng, 14, 32), h = uniform(rng, 12, 28);
  const double a = uniform(rng, 6, 0.45 * w), b = uniform(rng, 6, 0.45 * h);
  if (kind == "l_shape") return {{{0, 0}, {w, 0}, {w, b}, {a, b}, {a, h}, {0, h}}, {}};
  if (kind == "t_shape") {
    const double s = std::max(6.0, 0.4 * w);
    return {{{w / 2 - s / 2, 0}, {w / 2 + s / 2, 0}, {w / 2 + s / 2, h - b}, {w, h - b}, {w, h}, {0, h}, {0, h - b}, {w / 2 - s / 2, h - b}}, {}};
  }
  if (kind == "u_shape") {
    const double arm = std::min(a, 0.3 * w);
    return {{{0, 0}, {w, 0}, {w, h}, {w - arm, h}, {w - arm, b}, {arm, b}, {arm, h}, {0, h}}, {}};
  }
  if (kind == "cut45") {
    const double c = uniform(rng, 4, 0.45 * std::min(w, h));
    return {{{0, 0}, {w, 0}, {w, h - c}, {w - c, h}, {0, h}}, {}};
  }
  if (kind == "courtyard") {
    const double W = std::max(w, 22.0), H = std::max(h, 20.0), t = uniform(rng, 6, 8);
    Ring hole = {{t, t}, {t, H - t}, {W - t, H - t}, {W - t, t}};  // clockwise
    return {rectangle(W, H), {hole}};
  }
  if (kind == "round") {
    const double r = uniform(rng, 6, 12);
    Ring ring;
    for (int k = 0; k < 72; ++k) ring.emplace_back(r + r * std::cos(2 * M_PI * k / 72), r + r * std::sin(2 * M_PI * k / 72));
    return {ring, {}};
  }
  if (kind == "irregular") {
    const int n = 5 + int(rng() % 3);
    const double r = uniform(rng, 8, 14);
    Ring ring;
    double angle = uniform(rng, 0, 0.5);
    for (int k = 0; k < n; ++k) {
      angle += 2 * M_PI / n * uniform(rng, 0.75, 1.25);
      if (angle >= 2 * M_PI) break;
      const double rk = r * uniform(rng, 0.85, 1.0);
      ring.emplace_back(r + rk * std::cos(angle), r + rk * std::sin(angle));
    }
    return {ring, {}};
  }
  return {rectangle(w, h), {}};
}

PolygonWithHoles transformed(const PolygonWithHoles& p, double angle, const Vec2& centre) {
  Vec2 mean = Vec2::Zero();
  for (const Vec2& q : p.outer) mean += q;
  mean /= double(p.outer.size());
  const Eigen::Rotation2Dd rotation(angle);
  auto apply = [&](Ring ring) {
    for (Vec2& q : ring) q = centre + rotation * (q - mean);
    return ring;
  };
  PolygonWithHoles out{apply(p.outer), {}};
  for (const Ring& h : p.holes) out.holes.push_back(apply(h));
  return out;
}

}  // namespace

namespace {

// A row of adjacent houses that a segmentation merges into one blob.
std::vector<SynthBuilding> row_of_houses(Rng& rng, double angle, const Vec2& centre) {
  const int count = 3 + int(rng() % 4);
  std::vector<double> widths;
  double total = 0;
  for (int k = 0; k < count; ++k) { widths.push_back(uniform(rng, 5.5, 8)); total += widths.back(); }
  std::vector<SynthBuilding> houses;
  double x = -total / 2;
  const Eigen::Rotation2Dd rotation(angle);
  for (int k = 0; k < count; ++k) {
    const double depth = uniform(rng, 9, 12);
    Ring ring = {{x, -5}, {x + widths[k], -5}, {x + widths[k], depth - 5}, {x, depth - 5}};
    for (Vec2& q : ring) q = centre + rotation * q;
    houses.push_back({{ring, {}}, "row_house", 0, 0});
    x += widths[k];
  }
  return houses;
}

double terrain(const Vec2& local) {
  return 2.0 + 0.01 * local.x() - 0.006 * local.y() + 0.8 * std::sin(local.x() / 70.0) * std::cos(local.y() / 90.0);
}

}  // namespace

// The segmentation of a true 0/1 mask: rounded corners, a smooth boundary wobble, speckles.
static cv::Mat segmentation_of(const cv::Mat& truth, const SynthOptions& o, Rng& rng) {
  const int rows = truth.rows, cols = truth.cols;
  const double px = o.pixel_size_m;
  const double noise_px = o.boundary_noise_m >= 0 ? wobble_rms_px(o.boundary_noise_m, px) : o.boundary_noise_px;
  const double radius_px = o.corner_radius_m >= 0 ? o.corner_radius_m / px : o.corner_radius_px;
  const double correlation_px = o.noise_wavelength_m > 0 ? wobble_correlation_px(o.noise_wavelength_m, px) : 3.0;
  const bool physical = o.boundary_noise_m >= 0 || o.corner_radius_m >= 0 || o.blur_m > 0 || o.bias_m != 0;
  cv::Mat mask = degrade_mask(truth, noise_px, radius_px, o.seed * 7919 + 2, correlation_px, physical,
                              std::max(0.0, o.blur_m) / px, o.bias_m / px);
  const int speckles = int(o.speckle_per_km2 * o.width_m * o.height_m / 1e6);
  const int speckle_px = o.speckle_size_m >= 0 ? std::max(1, int(std::lround(o.speckle_size_m / px))) : 0;
  for (int k = 0; k < speckles; ++k) {
    const int c = int(rng() % cols), r = int(rng() % rows), random_size = 1 + int(rng() % 2);
    const int size = speckle_px > 0 ? speckle_px : random_size;
    const cv::Rect box = cv::Rect(c, r, size, size) & cv::Rect(0, 0, cols, rows);
    mask(box).setTo(mask.at<uint8_t>(r, c) ? 0 : 1);
  }
  return mask;
}

SynthCity generate_city(const SynthOptions& o) {
  SynthCity city;
  Rng rng(o.seed);
  const int cols = std::max(1, int(std::lround(o.width_m / o.pixel_size_m)));
  const int rows = std::max(1, int(std::lround(o.height_m / o.pixel_size_m)));
  city.transform.c = {o.origin_x, o.pixel_size_m, 0, o.origin_y, 0, -o.pixel_size_m};
  static const std::vector<std::string> kinds = {"rectangle", "rectangle", "l_shape", "t_shape", "u_shape", "cut45",
                                                 "courtyard", "row_house", "row_house", "round", "irregular"};
  const double pitch = 48.0;
  const double district_angle = uniform(rng, 0, M_PI / 2);
  for (double cy = pitch / 2; cy + pitch / 2 <= o.height_m + 1e-9; cy += pitch) {
    for (double cx = pitch / 2; cx + pitch / 2 <= o.width_m + 1e-9; cx += pitch) {
      const std::string kind = kinds[rng() % kinds.size()];
      const double pick = uniform(rng, 0, 1);
      const double angle = pick < 0.4 ? 0.0 : pick < 0.7 ? district_angle : uniform(rng, 0, M_PI / 2);
      const Vec2 centre(o.origin_x + cx + uniform(rng, -3, 3), o.origin_y - cy + uniform(rng, -3, 3));
      if (kind == "row_house") {
        for (SynthBuilding& b : row_of_houses(rng, angle, centre)) city.buildings.push_back(std::move(b));
      } else {
        city.buildings.push_back({transformed(make_shape(kind, rng), angle, centre), kind, 0, 0});
      }
    }
  }
  // Heights: a sloped, gently rolling terrain; flat roofs 5–30 m above it.
  city.dtm.create(rows, cols, CV_32F);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      city.dtm.at<float>(r, c) = float(terrain({(c + 0.5) * o.pixel_size_m, (r + 0.5) * o.pixel_size_m}));
  city.dsm = city.dtm.clone();
  cv::Mat truth = cv::Mat::zeros(rows, cols, CV_8U);
  for (SynthBuilding& b : city.buildings) {
    const Vec2 corner = b.footprint.outer.front();
    b.ground_height = terrain({corner.x() - o.origin_x, o.origin_y - corner.y()});
    b.roof_height = b.ground_height + uniform(rng, 5, 30);
    rasterize(truth, b.footprint, city.transform);
    // The roof, in the footprint's bounding box only (a whole-raster mask per building made
    // generation quadratic in the area).
    const cv::Rect box = pixel_box(b.footprint, city.transform, 1, cv::Size(cols, rows));
    if (box.empty()) continue;
    cv::Mat roof = cv::Mat::zeros(box.size(), CV_8U);
    rasterize(roof, b.footprint, city.transform.window(box.x, box.y));
    city.dsm(box).setTo(cv::Scalar(b.roof_height), roof);
  }
  cv::Mat height_noise(rows, cols, CV_32F);
  cv::RNG cv_rng(o.seed * 7919 + 1);
  cv_rng.fill(height_noise, cv::RNG::NORMAL, 0, 0.05);
  city.dsm += height_noise;

  city.building_mask = segmentation_of(truth, o, rng);
  return city;
}

SynthCity segment_footprints(const std::vector<PolygonWithHoles>& footprints, const SynthOptions& options) {
  if (footprints.empty()) throw std::invalid_argument("no footprints to segment");
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const PolygonWithHoles& f : footprints)
    for (const Vec2& p : f.outer) {
      x0 = std::min(x0, p.x()); y0 = std::min(y0, p.y());
      x1 = std::max(x1, p.x()); y1 = std::max(y1, p.y());
    }
  const double px = options.pixel_size_m, margin = 10.0;
  SynthOptions o = options;
  o.origin_x = std::floor((x0 - margin) / px) * px;
  o.origin_y = std::ceil((y1 + margin) / px) * px;
  const int cols = int(std::ceil((x1 + margin - o.origin_x) / px)), rows = int(std::ceil((o.origin_y - (y0 - margin)) / px));
  o.width_m = cols * px;
  o.height_m = rows * px;
  SynthCity city;
  city.transform.c = {o.origin_x, px, 0, o.origin_y, 0, -px};
  cv::Mat truth = cv::Mat::zeros(rows, cols, CV_8U);
  for (const PolygonWithHoles& f : footprints) {
    // Each footprint on its own, then OR-ed in: a hole must not erase a building standing in it.
    const cv::Rect box = pixel_box(f, city.transform, 1, cv::Size(cols, rows));
    cv::Mat own = cv::Mat::zeros(box.size(), CV_8U);
    rasterize(own, f, city.transform.window(box.x, box.y));
    truth(box) |= own;
    city.buildings.push_back({f, "given", 0, 0});
  }
  Rng rng(o.seed);
  city.building_mask = segmentation_of(truth, o, rng);
  return city;
}

namespace {

// Opening of a 0/1 mask by a disc of any real radius (pixels), from Euclidean distances between
// pixel centres: exact whatever the radius, and as fast for a radius of 20 pixels as of 1.
cv::Mat euclidean_open(const cv::Mat& mask, double radius) {
  cv::Mat distance, eroded, grown;
  cv::distanceTransform(mask, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);  // to the nearest 0
  eroded = distance > radius;                                                 // 0 / 255
  cv::Mat outside = 255 - eroded;
  cv::distanceTransform(outside, grown, cv::DIST_L2, cv::DIST_MASK_PRECISE);  // to the eroded set
  cv::Mat opened = grown <= radius;
  return opened / 255;
}

// The noise field made constant across the boundary: each pixel takes the value of the nearest
// pixel on the other side (OpenCV labels the zero pixels 1, 2, ... in scan order), so the level
// set is the boundary displaced along its normal, a wobble along it, not a fringe of islands.
cv::Mat noise_of_nearest_boundary(const cv::Mat& mask, const cv::Mat& noise) {
  cv::Mat out(mask.size(), CV_32F), distance, labels_in, labels_out;
  cv::distanceTransform(mask, distance, labels_in, cv::DIST_L2, cv::DIST_MASK_5, cv::DIST_LABEL_PIXEL);
  const cv::Mat inverse = 1 - mask;
  cv::distanceTransform(inverse, distance, labels_out, cv::DIST_L2, cv::DIST_MASK_5, cv::DIST_LABEL_PIXEL);
  std::vector<float> at_outside{0.0f}, at_inside{0.0f};  // by label
  for (int r = 0; r < mask.rows; ++r)
    for (int c = 0; c < mask.cols; ++c) (mask.at<uint8_t>(r, c) ? at_inside : at_outside).push_back(noise.at<float>(r, c));
  for (int r = 0; r < mask.rows; ++r)
    for (int c = 0; c < mask.cols; ++c)
      out.at<float>(r, c) = mask.at<uint8_t>(r, c) ? at_outside[labels_in.at<int>(r, c)] : at_inside[labels_out.at<int>(r, c)];
  return out;
}

}  // namespace

double wobble_rms_px(double amplitude_m, double pixel_size) { return amplitude_m / std::sqrt(2.0) / pixel_size; }

// A Gaussian-blurred white noise of blur s has the correlation exp(-d^2 / 4s^2): its level
// crosses zero every pi * sqrt(2) * s on average (Rice), a wavelength of 2 pi sqrt(2) s.
double wobble_correlation_px(double wavelength_m, double pixel_size) {
  return wavelength_m / (2 * M_PI * std::sqrt(2.0)) / pixel_size;
}

cv::Mat degrade_mask(const cv::Mat& truth, double noise_px, double corner_radius_px, std::uint64_t seed,
                     double correlation_px, bool physical, double blur_px, double bias_px) {
  const int rows = truth.rows, cols = truth.cols;
  cv::Mat mask = truth.clone();
  const int radius = int(std::lround(corner_radius_px));
  if (physical) {
    if (corner_radius_px > 0) {
      mask = euclidean_open(mask, corner_radius_px);
      mask = 1 - euclidean_open(1 - mask, corner_radius_px);  // a closing
    }
  } else if (radius > 0) {
    const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * radius + 1, 2 * radius + 1});
    cv::morphologyEx(mask, mask, cv::MORPH_OPEN, kernel);
    cv::morphologyEx(mask, mask, cv::MORPH_CLOSE, kernel);
  }
  const bool blur = physical && blur_px > 0, bias = physical && bias_px != 0;
  if (noise_px <= 0 && !blur && !bias) return mask;
  // The boundary's displacement along its normal at each pixel (pixels, outwards): the wobble and
  // the bias.
  cv::Mat shift = cv::Mat(rows, cols, CV_32F, cv::Scalar(physical ? bias_px : 0.0));
  if (noise_px > 0) {
    cv::RNG cv_rng(seed);
    cv::Mat noise(rows, cols, CV_32F);
    cv_rng.fill(noise, cv::RNG::NORMAL, 0, 1);
    if (correlation_px >= 0.2) cv::GaussianBlur(noise, noise, {0, 0}, correlation_px);
    cv::Scalar mean, stddev;
    cv::meanStdDev(noise, mean, stddev);
    noise = noise * (noise_px / std::max(stddev[0], 1e-9));
    if (physical) noise = noise_of_nearest_boundary(mask, noise);
    shift += noise;
  }
  if (blur) {
    // A network's smoothing: the mask blurred by a Gaussian of blur_px, and kept where it is above
    // the level a straight wall's blurred step takes at the displaced boundary, Phi(-shift / blur):
    // along a straight wall the boundary moves by the shift exactly, a corner is cut (convex) or
    // filled (concave) along a few blurs. The shift is taken at most four blurs either way, where
    // the blurred step is flat to a few parts in 10^5 (beyond, a rounding error of the blur would
    // decide, and a building lose pixels deep inside).
    cv::Mat blurred;
    mask.convertTo(blurred, CV_32F);
    cv::GaussianBlur(blurred, blurred, {0, 0}, blur_px);
    cv::Mat out(rows, cols, CV_8U);
    const double most = 4 * blur_px, width = blur_px * std::sqrt(2.0);
    // (Every level lies between these two, the shift clamped: a pixel blurred to at most the lowest
    // is out, one above the highest in, without its level.)
    const double lowest = 0.5 * std::erfc(most / width), highest = 0.5 * std::erfc(-most / width);
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) {
        const double value = blurred.at<float>(r, c);
        if (value <= lowest || value > highest) {
          out.at<uint8_t>(r, c) = value > highest ? 1 : 0;
          continue;
        }
        const double moved = std::clamp(double(shift.at<float>(r, c)), -most, most);
        out.at<uint8_t>(r, c) = value > 0.5 * std::erfc(moved / width) ? 1 : 0;
      }
    return out;
  }
  cv::Mat inside, outside, inverse = 1 - mask;
  cv::distanceTransform(mask, inside, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::distanceTransform(inverse, outside, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::Mat signed_distance(rows, cols, CV_32F);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      signed_distance.at<float>(r, c) = mask.at<uint8_t>(r, c) ? inside.at<float>(r, c) - 0.5f
                                                                : 0.5f - outside.at<float>(r, c);
  mask = (signed_distance + shift) > 0;
  mask /= 255;
  return mask;
}

}  // namespace lodforge
