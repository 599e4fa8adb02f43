// A quick-look picture per tile: the LOD0 outlines over the orthophoto, or over a hillshade of
// the DSM where there is none (or over the segmentation mask without either).
#pragma once
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "geometry/geotransform.hpp"
#include "geometry/types.hpp"

namespace lodforge {

struct QuicklookOutline {
  PolygonWithHoles footprint;
  bool ok = true;  // ok: red; fallback: yellow
};

// Grey hillshade (CV_8UC3) of a DSM window (sun from the north-west, 45° high); invalid pixels black.
cv::Mat hillshade(const cv::Mat& dsm, const cv::Mat& valid, double pixel_size);

// Draws the outlines on background (CV_8UC3, georeferenced by transform) and writes a PNG,
// atomically. Throws InputError if it cannot be written.
void write_quicklook(const std::string& path, cv::Mat background, const GeoTransform& transform,
                     const std::vector<QuicklookOutline>& outlines);

}  // namespace lodforge
