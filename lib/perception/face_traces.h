// SPDX-License-Identifier: Apache-2.0
// How the lasers' traces meet a fitted face (informative_face.h): a laser's returns near an edge, whether
// they run along it or cross it, and how far that says the face's direction may be from the footprint's.
// A laser's trace along a vertical surface is a line in plan; where a fitted edge is a chord of traces,
// not a surface they run along, its points say less about its direction than their number suggests.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "perception/lidar_geometry.h"

namespace rsu::perception {

// The median of v (reorders it).
double median_in_place(std::vector<double>& v);
// The length of an evenly spread face whose direction a line fit knows as well as it does from points at
// `along` (a least-squares slope's variance is sigma^2 / sum (s - mean)^2; evenly over l that sum is n l^2
// / 12): sqrt(12) times their RMS spread about their mean.
double spread_length(std::span<const double> along);
// The least-squares slope of n over s (0 for fewer than two distinct s).
double least_squares_slope(std::span<const double> s, std::span<const double> n);

// A fitted edge: from a along the unit vector t over length, its support band d either side.
struct FaceLine {
  Eigen::Vector2d a;
  Eigen::Vector2d t;
  double length = 0.0;
  double band = 0.0;
};

// A laser's return near a face: where along and across it, its height, its laser's rank and its index
// into the points.
struct TracePoint {
  double along = 0.0;
  double across = 0.0;
  double z = 0.0;
  std::size_t laser = 0;
  std::size_t index = 0;
};

// The lasers' returns near `edge`, in the order they came (each laser's, a trace), with their laser ranks
// (ranks: LaserLookup::ranks of points): over the edge's length and its band beyond either end, at most
// `depth` across it, at any height.
std::vector<TracePoint> traces_near(std::span<const Eigen::Vector3d> points,
                                    std::span<const std::size_t> ranks, const FaceLine& edge, double depth);

// A laser's points inside a face's span (away from its corners), across it: s along, n across, and how
// many lie in its support band.
struct SpanTrace {
  std::vector<double> along, across;
  std::size_t in_band = 0;
};

// Of each of `lasers` lasers' returns near `edge` (traces_near), those within its span away from its corners
// by its support band and at most `max_height` above the road at ground_z (the full plan, side_body_height:
// not a roof's or bonnet's level arc).
std::vector<SpanTrace> span_traces(const std::vector<TracePoint>& near, std::size_t lasers,
                                   const FaceLine& edge, double ground_z, double max_height);

// The departure of a face that is a chord of a laser's trace, not a surface the trace runs along: at least
// three quarters of a laser's points within the face's span lie off its support band, on one straight line
// across it (within collinear_m; a vertical surface seen by one laser is a line in plan), and only where that
// line crosses the band do they count for the face (with half or more off it, the HDL-32E's and 64-ring
// sensor's coupes lost 0.7-3.7 points of cells under 0.10 m). Its direction is the trace's, tilted from the
// face's by the slope k: a departure of |k| over half the face. A VLP-16 6 m up saw a coupe's side 34 m away
// with one laser (40 returns, its lower body's outline a clump at one end and one return at the other); the
// fitted "side" held 5 of them over 1.4 m where the trace crossed it at 15 deg, stating 4-5 deg, 12-15 deg
// off (a third pilot matrix, kept out of the repository).
double crossing_trace_departure(const std::vector<SpanTrace>& traces, double length, double collinear_m);

// A laser's runs along a face: its returns in a row (in the order they came, a trace's) within the face's
// support band; a return of the same laser off the band but near the face ends one. For each return near
// the face (traces_near), its run (LaserLookup::kNone: off the band), and each run's size.
struct TraceRuns {
  std::vector<std::size_t> run;
  std::vector<std::size_t> size;
};

TraceRuns trace_runs(const std::vector<TracePoint>& near, std::size_t lasers, const FaceLine& edge);

// Which of `count` points lie in runs of fewer than min_points: where a laser's trace crosses the face
// (leaving its support band on both sides within a few returns), not a surface along it.
std::vector<bool> crossing_returns(const std::vector<TracePoint>& near, const TraceRuns& runs,
                                   std::size_t count, std::size_t min_points);

// How far runs of min_points or more tilt from the face: the steepest of their least-squares slopes beyond
// twice its standard error (noise_sigma across each return, as evenly spread along the run), as a
// departure over half the face's length. Such runs lie on surfaces not parallel to one another (sloped
// glass, a roof's edge, a windscreen's foot): the face fitted through them lies between their directions,
// and the footprint's may be any of them.
double run_tilt_departure(const std::vector<TracePoint>& near, const TraceRuns& runs, double length,
                          double noise_sigma, std::size_t min_points);

}  // namespace rsu::perception
