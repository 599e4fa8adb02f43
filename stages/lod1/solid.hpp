// Stage 9: the LOD1 block, the footprint (with its holes, which become inner walls) extruded from
// ground to roof, and the checks val3dity makes on a shell: closed 2-manifold, outward faces,
// planar faces, no duplicate vertex or degenerate face.
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "geometry/types.hpp"

namespace lodforge {

using Vec3 = Eigen::Vector3d;
using Ring3 = std::vector<Vec3>;

struct Face {
  std::vector<Ring3> rings;  // [0] outer, then holes; counter-clockwise seen from outside
};

struct Solid {
  std::vector<Face> faces;  // bottom, top, then the walls of the outer ring and of every hole
};

Solid extrude(const PolygonWithHoles& footprint, double ground, double roof);

// Empty when the shell is valid; else the first problem found.
std::string shell_problem(const Solid& solid, double tolerance = 1e-6);

double volume(const Solid& solid);  // > 0 when the faces point outward

}  // namespace lodforge
