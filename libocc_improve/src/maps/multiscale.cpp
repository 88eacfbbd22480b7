#include "occ_improve/maps/multiscale.hpp"

#include "occ_improve/planning/depth_prediction.hpp"
#include "occ_improve/errors.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace occ_improve {

void BlockSummary::add(const BlockSummary& o) {
  improvement_sum += o.improvement_sum;
  observable_rays += o.observable_rays;
  samples += o.samples;
  su += o.su, sv += o.sv, sz += o.sz, suu += o.suu, suv += o.suv, svv += o.svv, suz += o.suz, svz += o.svz,
      szz += o.szz;
}

float BlockSummary::mean_improvement() const {
  return observable_rays ? improvement_sum / static_cast<float>(observable_rays) : std::numeric_limits<float>::quiet_NaN();
}

int ImprovementPyramid::level_of_block_size(int columns) {
  for (int level = 0; level < kLevels; ++level)
    if (block_size(level) == columns) return level;
  detail::require_parameter(false, "block size (columns)", columns, "one of 2, 4, 8, 16");
  return 0;
}

ImprovementPyramid::ImprovementPyramid(const ImprovementMap& improvement, const SurfaceMap& surface)
    : width_(improvement.width), height_(improvement.height) {
  check_maps(improvement, surface);
  for (int level = 0; level < kLevels; ++level) {
    levels_[level].assign(block_count(level), BlockSummary{});
    marks_[level].assign(block_count(level), 0);
    for (std::size_t b = 0; b < levels_[level].size(); ++b) recompute(level, b, improvement, surface);
  }
}

void ImprovementPyramid::check_maps(const ImprovementMap& improvement, const SurfaceMap& surface) const {
  require_shape("improvement map", improvement.shape(), "the pyramid", shape());
  require_shape("surface map", surface.shape(), "the pyramid", shape());
}

int ImprovementPyramid::blocks_x(int level) const {
  const int s = block_size(level);
  return (width_ + s - 1) / s;
}
int ImprovementPyramid::blocks_y(int level) const {
  const int s = block_size(level);
  return (height_ + s - 1) / s;
}
std::size_t ImprovementPyramid::block_count(int level) const {
  return static_cast<std::size_t>(blocks_x(level)) * static_cast<std::size_t>(blocks_y(level));
}

const BlockSummary& ImprovementPyramid::block(int level, int bx, int by) const {
  detail::require_parameter(level >= 0 && level < kLevels, "level", level, "in [0, 4)");
  detail::require_parameter(bx >= 0 && bx < blocks_x(level), "bx", bx, "inside the level's blocks");
  detail::require_parameter(by >= 0 && by < blocks_y(level), "by", by, "inside the level's blocks");
  return levels_[level][static_cast<std::size_t>(by) * static_cast<std::size_t>(blocks_x(level)) + static_cast<std::size_t>(bx)];
}

const BlockSummary& ImprovementPyramid::block_at(int level, std::size_t index) const {
  detail::require_parameter(level >= 0 && level < kLevels, "level", level, "in [0, 4)");
  detail::require_parameter(index < block_count(level), "index", static_cast<double>(index), "below the level's block count");
  return levels_[level][index];
}

std::size_t ImprovementPyramid::block_of_column(int level, ColumnIndex c) const {
  const int s = block_size(level);
  const auto u = static_cast<int>(c % static_cast<ColumnIndex>(width_)), v = static_cast<int>(c / static_cast<ColumnIndex>(width_));
  return static_cast<std::size_t>(v / s) * static_cast<std::size_t>(blocks_x(level)) + static_cast<std::size_t>(u / s);
}

// Level 0 from its (up to) 2 x 2 fine columns, higher levels from their (up to) 2 x 2 children, always in
// row-major order: a rebuild and an update add the same numbers in the same order.
void ImprovementPyramid::recompute(int level, std::size_t b, const ImprovementMap& improvement, const SurfaceMap& surface) {
  const int bx = static_cast<int>(b % static_cast<std::size_t>(blocks_x(level)));
  const int by = static_cast<int>(b / static_cast<std::size_t>(blocks_x(level)));
  BlockSummary sum;
  if (level == 0) {
    for (int v = 2 * by; v < std::min(height_, 2 * by + 2); ++v)
      for (int u = 2 * bx; u < std::min(width_, 2 * bx + 2); ++u) {
        const std::size_t c = static_cast<std::size_t>(v) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(u);
        const float imp = improvement.value[c];
        if (!std::isnan(imp)) {
          sum.improvement_sum += imp;
          ++sum.observable_rays;
        }
        if (!is_depth_sample(surface, c)) continue;
        const double z = surface.depth_m[c], uu = u + 0.5, vv = v + 0.5;
        ++sum.samples;
        sum.su += uu, sum.sv += vv, sum.sz += z, sum.suu += uu * uu, sum.suv += uu * vv, sum.svv += vv * vv,
            sum.suz += uu * z, sum.svz += vv * z, sum.szz += z * z;
      }
  } else {
    const std::vector<BlockSummary>& below = levels_[level - 1];
    const int cx = blocks_x(level - 1), cy = blocks_y(level - 1);
    for (int y = 2 * by; y < std::min(cy, 2 * by + 2); ++y)
      for (int x = 2 * bx; x < std::min(cx, 2 * bx + 2); ++x)
        sum.add(below[static_cast<std::size_t>(y) * static_cast<std::size_t>(cx) + static_cast<std::size_t>(x)]);
  }
  levels_[level][b] = sum;
}

void ImprovementPyramid::update(const ImprovementMap& improvement, const SurfaceMap& surface,
                                const std::vector<ColumnIndex>& changed) {
  check_maps(improvement, surface);
  const auto cells = static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
  for (const ColumnIndex c : changed)
    if (c >= cells)
      throw InvalidInput("changed column " + std::to_string(c) + " is outside the grid (" + std::to_string(cells) +
                         " columns)");
  // Blocks to recompute per level, each once (a mark per block, cleared again: cost proportional to the
  // change, no pass over the level): the level-0 blocks of the changed columns, then their parents.
  std::vector<std::size_t> dirty, parents;
  dirty.reserve(changed.size() / 2);
  for (const ColumnIndex c : changed) {
    const std::size_t b = block_of_column(0, c);
    if (!marks_[0][b]) marks_[0][b] = 1, dirty.push_back(b);
  }
  for (int level = 0; level < kLevels; ++level) {
    for (const std::size_t b : dirty) {
      recompute(level, b, improvement, surface);
      marks_[level][b] = 0;
    }
    if (level + 1 == kLevels) break;
    const auto across = static_cast<std::size_t>(blocks_x(level)), parent_across = static_cast<std::size_t>(blocks_x(level + 1));
    parents.clear();
    for (const std::size_t b : dirty) {
      const std::size_t p = (b / across / 2) * parent_across + (b % across) / 2;
      if (!marks_[level + 1][p]) marks_[level + 1][p] = 1, parents.push_back(p);
    }
    dirty.swap(parents);
  }
}

double ImprovementPyramid::residual_sigmas(int level, int bx, int by, const SensorModel& model, LocalModel local) const {
  block(level, bx, by);  // checks the arguments
  BlockSummary m;
  for (int y = std::max(0, by - 1); y <= std::min(blocks_y(level) - 1, by + 1); ++y)
    for (int x = std::max(0, bx - 1); x <= std::min(blocks_x(level) - 1, bx + 1); ++x) m.add(block(level, x, y));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double n = m.samples;
  if (m.samples < (local == LocalModel::constant ? 2u : 4u)) return nan;
  // Centred moments: the least-squares constant leaves czz, the plane czz - (a cuz + b cvz).
  const double cuu = m.suu - m.su * m.su / n, cuv = m.suv - m.su * m.sv / n, cvv = m.svv - m.sv * m.sv / n;
  const double cuz = m.suz - m.su * m.sz / n, cvz = m.svz - m.sv * m.sz / n, czz = m.szz - m.sz * m.sz / n;
  double sse = czz;
  const double det = cuu * cvv - cuv * cuv;
  // Collinear samples (det ~ 0 relative to the spread) fix no plane: the constant's residual stands.
  if (local == LocalModel::plane && det > 1e-9 * cuu * cvv && det > 0) {
    const double a = (cuz * cvv - cvz * cuv) / det, b = (cvz * cuu - cuz * cuv) / det;
    sse = czz - a * cuz - b * cvz;
  }
  const double rms = std::sqrt(std::max(0.0, sse) / n);
  return rms / model.sigma_depth_at(m.sz / n);
}

std::size_t ImprovementPyramid::memory_bytes() const {
  std::size_t bytes = 0;
  for (int level = 0; level < kLevels; ++level)
    bytes += levels_[level].capacity() * sizeof(BlockSummary) + marks_[level].capacity();
  return bytes;
}

}  // namespace occ_improve
