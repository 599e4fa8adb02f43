// Every option of the per-building core, declared once (see common/option.hpp).
#pragma once
#include "common/option.hpp"
#include "contour/contour.hpp"
#include "corners/corners.hpp"
#include "deformation/deform.hpp"
#include "directions/lattice.hpp"
#include "directions/ransac.hpp"
#include "directions/refine.hpp"
#include "labeling/mrf.hpp"
#include "models/noise.hpp"
#include "models/rectangle.hpp"
#include "normals/smoothing.hpp"
#include "peers/cgal_contours.hpp"
#include "triangulation/triangulate.hpp"

namespace lodforge {

struct FallbackOptions {
  double tolerance_m = 0.5;  // Douglas–Peucker tolerance of the fallback footprint

  template <class V>
  void visit(V& v) {
    v("tolerance_m", tolerance_m, "Douglas-Peucker tolerance of the fallback footprint (m)", Check::at_least(0));
  }
};

// Bounds on the work spent on one building, so a pathological contour never hangs a run.
// Edge and iteration limits are deterministic; the time limit is a safety net (a building that
// hits it is reported as failed, with the fallback footprint).
struct BudgetOptions {
  int max_edges = 200000;             // contours with more edges get the fallback
  int max_deformation_edges = 20000;  // larger contours skip the deformation route
  int max_mesh_vertices = 600;        // the deformation mesh is coarsened to about this many vertices
  double max_deformation_work = 1.2e5; // mesh vertices x Newton iterations; beyond: the original route
  double max_seconds = 60.0;          // per building

  template <class V>
  void visit(V& v) {
    v("max_edges", max_edges, "contours with more boundary edges get the fallback footprint", Check::at_least(3));
    v("max_deformation_edges", max_deformation_edges, "contours with more edges are not deformed (they take the 'original' route)", Check::at_least(3));
    v("max_mesh_vertices", max_mesh_vertices, "the deformation mesh is kept to about this many vertices: each labeled run is simplified further and the mesh edges grow beyond triangulation.size_bound_px until it fits (0 = no bound, the paper's full mesh)", Check::at_least(0));
    v("max_deformation_work", max_deformation_work, "the deformation stops after this many mesh vertices x Newton iterations, and the building takes the 'original' route, the reason recorded (0 = no bound)", Check::at_least(0));
    v("max_seconds", max_seconds, "time limit per building (s), from the start of its chain (in `regularize`, the normals smoothed first to pool the mask's noise are counted in its time but not here); a building over it gets the fallback", Check::above(0));
  }
};

struct CoreOptions {
  SmoothingOptions smoothing;
  RansacOptions directions;
  MrfOptions labeling;
  NoiseOptions noise;
  RefineOptions refinement;
  LatticeOptions lattice;
  TriangulationOptions triangulation;
  DeformationOptions deformation;
  CornerOptions corners;
  ModelOptions models;
  FallbackOptions fallback;
  BudgetOptions budget;
  CgalContourOptions cgal;  // the 'cgal' peer regularizer

  template <class V>
  void visit(V& v) {
    v.section("smoothing", smoothing);
    v.section("directions", directions);
    v.section("labeling", labeling);
    v.section("noise", noise);
    v.section("refinement", refinement);
    v.section("lattice", lattice);
    v.section("triangulation", triangulation);
    v.section("deformation", deformation);
    v.section("corners", corners);
    v.section("models", models);
    v.section("fallback", fallback);
    v.section("budget", budget);
    v.section("cgal", cgal);
  }
};

}  // namespace lodforge
