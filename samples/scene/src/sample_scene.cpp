#include "occ_improve/sample_scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace occ_improve::sample {

namespace {

struct Box {
  Eigen::Vector3d lo, hi;
};

// Slab test; returns the entry distance along the ray or +inf.
double hit_box(const Box& b, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-12) {
      if (o[i] < b.lo[i] || o[i] > b.hi[i]) return std::numeric_limits<double>::infinity();
      continue;
    }
    double a = (b.lo[i] - o[i]) / d[i], c = (b.hi[i] - o[i]) / d[i];
    if (a > c) std::swap(a, c);
    t0 = std::max(t0, a);
    t1 = std::min(t1, c);
  }
  return t0 <= t1 && t0 > 1e-9 ? t0 : std::numeric_limits<double>::infinity();
}

class Scene {
public:
  Scene() {
    const double floor_y = 0.8;
    boxes_ = {
        {{-6.0, floor_y, 0.0}, {6.0, floor_y + 0.1, 7.0}},   // floor slab
        {{-6.0, -3.0, 4.2}, {0.6, floor_y, 4.4}},            // back wall, left part
        {{0.6, -3.0, 6.5}, {6.0, floor_y, 6.7}},             // recess beyond 5 m
        {{-0.9, 0.1, 1.6}, {-0.3, floor_y, 2.0}},            // box occluder
        {{0.35, -1.5, 2.3}, {0.45, floor_y, 2.4}},           // thin pole
    };
  }
  // Distance along the unit ray and the index of the box hit (-1 for none).
  double cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d, int* which = nullptr) const {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < boxes_.size(); ++i) {
      const double t = hit_box(boxes_[i], o, d);
      if (t < best) {
        best = t;
        if (which) *which = static_cast<int>(i);
      }
    }
    return best;
  }

private:
  std::vector<Box> boxes_;
};

bool in_poster(const Eigen::Vector3d& p) {  // the dark poster on the back wall
  return p.z() > 4.19 && p.z() < 4.21 && p.x() > -1.6 && p.x() < -1.0 && p.y() > -0.6 && p.y() < 0.1;
}

}  // namespace

std::vector<Eigen::Vector3f> SampleFrame::points() const {
  std::vector<Eigen::Vector3f> out(depth_m.size());
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 0; v < intrinsics.height; ++v)
    for (int u = 0; u < intrinsics.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * static_cast<std::size_t>(intrinsics.width) +
                            static_cast<std::size_t>(u);
      const float z = depth_m[i];
      out[i] = z > 0 ? Eigen::Vector3f(static_cast<float>((u - intrinsics.cx) * z / intrinsics.fx),
                                       static_cast<float>((v - intrinsics.cy) * z / intrinsics.fy), z)
                     : Eigen::Vector3f(nan, nan, nan);
    }
  return out;
}

SampleFrame generate_scene(const SceneOptions& options) {
  SampleFrame f;
  // A real Kinect v1 depth camera: f = 585 px gives the 57 deg field of view the paper's grid spans
  // (OpenNI's nominal 525 px would make pixels coarser than the grid's columns).
  f.intrinsics = PinholeIntrinsics{585.0, 585.0, 319.5, 239.5, 640, 480};
  const PinholeIntrinsics& k = f.intrinsics;
  f.depth_m.assign(static_cast<std::size_t>(k.width) * static_cast<std::size_t>(k.height), 0.0f);
  const Scene scene;
  const Eigen::Vector3d camera(0, 0, 0), projector(0.075, 0, 0);
  const double focal_baseline = k.fx * 0.075;  // disparity (pixels) = focal_baseline / z
  std::mt19937 rng(options.seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector3d d = Eigen::Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0).normalized();
      const double t = scene.cast(camera, d);
      const double noise = unit(rng);  // drawn for every pixel so frames stay aligned across seeds
      if (!std::isfinite(t)) continue;
      const Eigen::Vector3d p = camera + t * d;
      if (in_poster(p)) continue;
      if (options.projector_shadow) {
        const Eigen::Vector3d to_p = p - projector;
        const double dist = to_p.norm();
        if (scene.cast(projector, to_p / dist) < dist - 1e-3) continue;  // projector cannot light p
      }
      double z = p.z();
      if (z > 8.0) continue;  // beyond what the sensor returns
      if (options.noise) z += 1.425e-3 * z * z * noise;
      if (options.quantise) z = focal_baseline / (std::round(focal_baseline / z * 8.0) / 8.0);
      f.depth_m[static_cast<std::size_t>(v) * static_cast<std::size_t>(k.width) + static_cast<std::size_t>(u)] =
          static_cast<float>(z);
    }
  return f;
}

std::vector<Eigen::Vector3f> render_range_image(const GridGeometry& g, const RangeImageOptions& o) {
  const Scene scene;
  std::mt19937 rng(o.seed);
  std::uniform_real_distribution<double> jitter(-1.0, 1.0);
  std::normal_distribution<double> unit(0.0, 1.0);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<Eigen::Vector3f> points(g.column_count(), Eigen::Vector3f(nan, nan, nan));
  for (int e = 0; e < g.height(); ++e)
    for (int a = 0; a < g.width(); ++a) {
      const BinAxis &h = g.azimuth(), &v = g.elevation();
      const double dh = jitter(rng) * o.jitter_horizontal * h.width(a), dv = jitter(rng) * o.jitter_vertical * v.width(e);
      const double noise = unit(rng);  // drawn for every column so frames stay aligned across options
      const Eigen::Vector3d d = g.direction_at(h.centre(a) + dh, v.centre(e) + dv);
      const double t = scene.cast(Eigen::Vector3d::Zero(), d);
      if (!(t <= o.max_range_m)) continue;
      points[g.column(a, e)] = ((t + o.sigma_range_m * noise) * d).cast<float>();
    }
  return points;
}

std::vector<SampleFrame> generate_sequence(int frames, std::uint32_t first_seed) {
  std::vector<SampleFrame> out;
  for (int i = 0; i < frames; ++i) {
    SceneOptions o;
    o.seed = first_seed + static_cast<std::uint32_t>(i);
    out.push_back(generate_scene(o));
  }
  return out;
}

}  // namespace occ_improve::sample
