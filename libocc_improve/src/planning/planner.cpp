#include "occ_improve/planning/planner.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/planning/depth_prediction.hpp"
#include "occ_improve/planning/good_rays.hpp"
#include "occ_improve/planning/ranking.hpp"
#include "occ_improve/planning/sample_triangulation.hpp"

#include <algorithm>
#include <iterator>
#include <cmath>
#include <limits>
#include <sstream>

namespace occ_improve {
namespace {

Shot rays_shot(const std::vector<float>& score, const PlanRequest& request) {
  const auto negative_budget = static_cast<std::size_t>(std::floor(request.negative_share * request.budget_rays));
  const std::uint8_t* mask = request.candidates.empty() ? nullptr : request.candidates.data();
  std::vector<ColumnIndex> negative;
  std::vector<std::uint8_t> rest;  // the mask without the negative rays taken, when there are any
  if (negative_budget > 0) {
    std::vector<float> flipped(score.size());
    std::vector<std::uint8_t> is_negative(score.size());
    for (std::size_t c = 0; c < score.size(); ++c) {
      flipped[c] = -score[c];
      is_negative[c] = (!mask || mask[c]) && score[c] < 0;
    }
    negative = best_columns(flipped, is_negative.data(), negative_budget);
    rest = mask ? request.candidates : std::vector<std::uint8_t>(score.size(), 1);
    for (ColumnIndex c : negative) rest[c] = 0;
    mask = rest.data();
  }
  Shot shot;
  shot.columns = best_columns(score, mask, static_cast<std::size_t>(request.budget_rays) - negative.size());
  shot.ranked_rays = shot.columns.size();
  for (ColumnIndex c : shot.columns) shot.expected_gain += score[c];
  shot.columns.insert(shot.columns.end(), negative.begin(), negative.end());
  return shot;
}

Shot window_shot(const std::vector<float>& score, int width, int height, const PlanRequest& request) {
  const int ww = request.window_width_columns, wh = request.window_height_columns;
  const auto w1 = static_cast<std::size_t>(width) + 1;
  std::vector<double> integral(w1 * (static_cast<std::size_t>(height) + 1), 0.0);  // summed-area table
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const std::size_t i = (static_cast<std::size_t>(y) + 1) * w1 + static_cast<std::size_t>(x) + 1;
      const float v = score[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)];
      integral[i] = (v == v ? v : 0.0) + integral[i - 1] + integral[i - w1] - integral[i - w1 - 1];  // NaN: adds nothing
    }
  const auto sum_at = [&](int x, int y) {
    const auto at = [&](int xx, int yy) { return integral[static_cast<std::size_t>(yy) * w1 + static_cast<std::size_t>(xx)]; };
    return at(x + ww, y + wh) - at(x, y + wh) - at(x + ww, y) + at(x, y);
  };
  int best_x = 0, best_y = 0;
  double best = sum_at(0, 0);
  for (int y = 0; y + wh <= height; ++y)
    for (int x = 0; x + ww <= width; ++x)
      if (const double s = sum_at(x, y); s > best) {
        best = s;
        best_x = x;
        best_y = y;
      }
  Shot shot;
  for (int y = best_y; y < best_y + wh; ++y)
    for (int x = best_x; x < best_x + ww; ++x)
      shot.columns.push_back(static_cast<ColumnIndex>(y) * static_cast<ColumnIndex>(width) + static_cast<ColumnIndex>(x));
  shot.expected_gain = best;
  return shot;
}

Shot decimation_shot(const std::vector<float>& score, int width, int height, const PlanRequest& request) {
  const int step = decimation_step(width, height, request.budget_rays);
  std::vector<double> sums(static_cast<std::size_t>(step) * static_cast<std::size_t>(step), 0.0);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const float v = score[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)];
      sums[static_cast<std::size_t>((y % step) * step + x % step)] += v == v ? v : 0.0;  // NaN: adds nothing
    }
  // Row-major order of offsets: the first maximum is the lowest (row, column) offset.
  const auto best = static_cast<int>(std::max_element(sums.begin(), sums.end()) - sums.begin());
  Shot shot;
  shot.columns = decimation_pattern(width, height, step, best % step, best / step);
  shot.expected_gain = sums[static_cast<std::size_t>(best)];
  return shot;
}


// coarse_to_fine's constants (planner.hpp says why).
constexpr double kCoverageMinReturn = 0.5;
constexpr std::size_t kBlocksPerRay = 4;
constexpr ColumnIndex kNoColumn = std::numeric_limits<ColumnIndex>::max();

// Per block of `level`: the eligible column of largest rank_key(score) (kNoColumn where none) and the
// block's return rate (R + 1) / (A + 1) over the asks the record holds for its columns, one pass. The rate
// complements the per-ray return probability, whose neighbourhood prior only reaches 8 columns: a block of
// a silent region (out of range, cropped, dark) falls after a few asks wherever they were.
struct BlockBest {
  std::vector<ColumnIndex> column;
  std::vector<float> return_rate;
  std::vector<std::uint32_t> measured;  ///< columns the record saw return at least once
};
BlockBest best_ray_per_block(const ImprovementPyramid& pyramid, int level, const std::vector<float>& score,
                             const std::uint8_t* eligible, const ReturnRecord& returns) {
  BlockBest best;
  best.column.assign(pyramid.block_count(level), kNoColumn);
  best.measured.assign(best.column.size(), 0);
  std::vector<std::uint64_t> best_key(best.column.size(), 0);
  std::vector<std::uint32_t> asked(best.column.size(), 0), returned(best.column.size(), 0);
  const int s = ImprovementPyramid::block_size(level), w = pyramid.width(), across = pyramid.blocks_x(level);
  for (int v = 0; v < pyramid.height(); ++v) {
    std::size_t b = static_cast<std::size_t>(v / s) * static_cast<std::size_t>(across);  // steps every s columns
    for (int u = 0, in_block = 0; u < w; ++u) {
      if (in_block == s) ++b, in_block = 0;
      ++in_block;
      const auto c = static_cast<ColumnIndex>(v) * static_cast<ColumnIndex>(w) + static_cast<ColumnIndex>(u);
      asked[b] += returns.asked()[c];
      returned[b] += returns.returned()[c];
      best.measured[b] += returns.returned()[c] > 0 ? 1u : 0u;
      if ((eligible && !eligible[c]) || std::isnan(score[c])) continue;
      const std::uint64_t key = rank_key(score[c], c);
      if (best.column[b] == kNoColumn || key > best_key[b]) best.column[b] = c, best_key[b] = key;
    }
  }
  best.return_rate.resize(best.column.size());
  for (std::size_t b = 0; b < best.column.size(); ++b)
    best.return_rate[b] = static_cast<float>((returned[b] + 1.0) / (asked[b] + 1.0));
  return best;
}

// r of a block, or of the nearest ancestor with enough samples; the cap where none has.
double inherited_residual(const ImprovementPyramid& pyramid, int level, std::size_t block, const SensorModel& model,
                          const PlanRequest& request) {
  int bx = static_cast<int>(block % static_cast<std::size_t>(pyramid.blocks_x(level)));
  int by = static_cast<int>(block / static_cast<std::size_t>(pyramid.blocks_x(level)));
  for (; level < ImprovementPyramid::kLevels; ++level, bx /= 2, by /= 2) {
    const double r = pyramid.residual_sigmas(level, bx, by, model, request.local_model);
    if (!std::isnan(r)) return std::min(r, request.residual_cap_sigmas);
  }
  // No samples within 3 x 3 blocks of 16: unseen (the coverage pass's job) or silent (asking again wastes
  // rays: measured, it cost the real scenes a third of their returns).
  return 0.0;
}

// `unmeasured`: the share of the block's rays without a measurement of their own (a return in the record;
// without a record, without a depth sample: a full frame's map).
double block_priority(const ImprovementPyramid& pyramid, int level, std::size_t block, double p, double unmeasured,
                      const SensorModel& model, const PlanRequest& request) {
  const BlockSummary& b = pyramid.block_at(level, block);
  // The magnitude of the block's mean improvement: missing data (0.324) and depth transitions (negative:
  // "regions of negative improvement can be re-acquired") high, settled blocks (~0.1 and less) low.
  const double improvement = std::abs(static_cast<double>(b.mean_improvement()));
  if (request.refine_by == RefineBy::improvement) return improvement * p;
  // The residual does not fall when a block is sampled (an edge stays an edge): the share of its rays
  // still unmeasured stands for what a new ray there can add to the prediction. Not the pyramid's depth
  // samples: a measurement's OPDF makes its 3 x 3 neighbours samples too, and counting them stopped the
  // refinement once every ray had a measured neighbour (measured: the quality stalled at 0.84-0.87).
  const double residual = inherited_residual(pyramid, level, block, model, request) / request.residual_cap_sigmas;
  const double geometric = residual * p * std::max(0.0, unmeasured);
  return request.refine_by == RefineBy::both ? geometric * improvement : geometric;
}

// With a candidate mask: the eligible observable rays, and per level the blocks holding one. A block
// without one can take no ray, so these, not the level's blocks, are what the refinement chooses among.
struct EligibleBlocks {
  std::size_t rays = 0;
  std::size_t blocks[ImprovementPyramid::kLevels] = {};
};
EligibleBlocks eligible_blocks(const ImprovementPyramid& pyramid, const std::vector<float>& score,
                               const std::vector<std::uint8_t>& eligible) {
  EligibleBlocks out;
  std::vector<std::uint8_t> holds[ImprovementPyramid::kLevels];
  for (int l = 0; l < ImprovementPyramid::kLevels; ++l) holds[l].assign(pyramid.block_count(l), 0);
  for (std::size_t c = 0; c < score.size(); ++c) {
    if (!eligible[c] || std::isnan(score[c])) continue;
    ++out.rays;
    for (int l = 0; l < ImprovementPyramid::kLevels; ++l) {
      std::uint8_t& h = holds[l][pyramid.block_of_column(l, static_cast<ColumnIndex>(c))];
      out.blocks[l] += h == 0 ? 1u : 0u;
      h = 1;
    }
  }
  return out;
}

// Refinement by blocks (improvement, residual, both): one ray per block of the level that leaves the
// priority room to choose, blocks holding a ray of this shot (`taken`) left out.
std::vector<ColumnIndex> refine_by_blocks(const ImprovementPyramid& pyramid, const SensorModel& model,
                                          const std::vector<float>& score, const std::vector<float>& probability,
                                          const std::vector<std::uint8_t>& eligible,
                                          const std::vector<ColumnIndex>& taken, const ReturnRecord& returns,
                                          const PlanRequest& request, std::size_t left) {
  // The level: with a candidate mask, of its blocks holding a candidate, for the rays the mask still
  // offers (counting the view's blocks, a 32 x 32 mask's shot took 9-64 of its 1024 rays: one per block
  // of 16, 8 or 4 it overlaps).
  std::size_t rays_left = left, usable[ImprovementPyramid::kLevels];
  for (int l = 0; l < ImprovementPyramid::kLevels; ++l) usable[l] = pyramid.block_count(l);
  if (!request.candidates.empty()) {
    const EligibleBlocks with_candidates = eligible_blocks(pyramid, score, eligible);
    rays_left = std::min(left, with_candidates.rays);
    std::copy(std::begin(with_candidates.blocks), std::end(with_candidates.blocks), usable);
  }
  int level = 0;
  for (int l = ImprovementPyramid::kLevels - 1; l >= 0; --l)
    if (usable[l] >= kBlocksPerRay * rays_left) {
      level = l;
      break;
    }
  std::vector<std::uint8_t> block_taken(pyramid.block_count(level), 0);
  for (ColumnIndex c : taken) block_taken[pyramid.block_of_column(level, c)] = 1;
  const BlockBest blocks = best_ray_per_block(pyramid, level, score, eligible.data(), returns);
  const std::vector<ColumnIndex>& best = blocks.column;
  std::vector<std::pair<std::uint64_t, std::size_t>> ranked;
  for (std::size_t b = 0; b < best.size(); ++b) {
    if (best[b] == kNoColumn || block_taken[b] || !(score[best[b]] > 0)) continue;
    const double p = static_cast<double>(probability[best[b]]) * blocks.return_rate[b];
    const BlockSummary& summary = pyramid.block_at(level, b);
    const double rays = summary.observable_rays ? summary.observable_rays : 1.0;
    const double unmeasured = returns.empty() ? 1.0 - summary.samples / rays : 1.0 - blocks.measured[b] / rays;
    const double priority = block_priority(pyramid, level, b, p, unmeasured, model, request);
    if (priority > 0) ranked.push_back({rank_key(static_cast<float>(priority), static_cast<ColumnIndex>(b)), b});
  }
  const std::size_t n = std::min(left, ranked.size());
  std::partial_sort(ranked.begin(), ranked.begin() + static_cast<std::ptrdiff_t>(n), ranked.end(),
                    [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<ColumnIndex> out(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = best[ranked[i].second];
  return out;
}

// The samples the refinement triangulates: the surface's depth at the rays that returned themselves (not
// the neighbours their OPDF reached, whose depth is borrowed); without a record, every depth sample.
std::vector<float> measured_depth_image(const SurfaceMap& surface, const ReturnRecord& returns) {
  std::vector<float> image = sample_depth_image(surface);
  if (returns.empty()) return image;
  for (std::size_t c = 0; c < image.size(); ++c)
    if (returns.returned()[c] == 0) image[c] = 0.0f;
  return image;
}

// Appends to `out`, up to `size` rays, the eligible observable rays of highest score, spread as a jittered
// grid (spread_best_columns: on the first shot every ray ties, and an even cover interpolates better than
// the clumps of a random sample).
void fill_by_score(const std::vector<float>& score, const std::vector<std::uint8_t>& eligible, int width,
                   std::size_t size, std::vector<ColumnIndex>& out) {
  if (out.size() >= size) return;
  const std::vector<ColumnIndex> best = spread_best_columns(score, eligible.data(), width, size - out.size());
  out.insert(out.end(), best.begin(), best.end());
}

// Refinement by triangles (the independent prototype of issue 20): the measured samples are
// triangulated in the image plane, and one ray goes to the centroid of each of the `left` triangles of
// largest area x non-planarity (capped at cap_sigmas) x return probability. A large triangle is a region
// the samples leave sparse; a non-planar one (a vertex off its neighbours' plane, in sigmas) is where the
// linear prediction is wrong; a flat, small one needs nothing. The centroid lies inside the triangle, so
// it is an unsampled ray between samples; one ray per triangle keeps a shot's rays apart.
// The centroids' expected gains in rays made good (good_rays.hpp) come back with them, in their order.
struct TriangleRefinement {
  std::vector<ColumnIndex> columns;  ///< the centroids, then the fill
  std::vector<double> centroid_gain;  ///< of columns[0, centroid_gain.size()): the centroids
};
TriangleRefinement refine_by_triangles(const SurfaceMap& surface, const SensorModel& model,
                                       const std::vector<float>& score, const std::vector<float>& probability,
                                       const std::vector<std::uint8_t>& eligible, const ReturnRecord& returns,
                                       double cap_sigmas, std::size_t left, SampleTriangulator* memory) {
  const std::vector<float> samples = measured_depth_image(surface, returns);
  // Neither a vertex (a sample) nor a ray asked before (measured, or silent): the centroid of a triangle
  // of a pixel or less rounds onto its own vertices.
  std::vector<std::uint8_t> unasked = eligible;
  std::size_t unasked_count = 0;
  for (std::size_t c = 0; c < unasked.size(); ++c) {
    if (samples[c] > 0.0f || (!returns.empty() && returns.asked()[c] > 0)) unasked[c] = 0;
    unasked_count += unasked[c];
  }
  // No centroid can be taken once every ray has been asked: the triangulation is then left as it is, and
  // the shot is the fill below. Without a memory, the samples are triangulated for this plan alone.
  SampleTriangulation this_plan;
  const SampleTriangulation& triangulation =
      unasked_count == 0 ? this_plan
      : memory           ? memory->update(samples, surface.width, surface.height, model)
                         : (this_plan = triangulate_samples(samples, surface.width, surface.height, model));
  struct Ranked {
    double priority;
    ColumnIndex column;     // the centroid's
    std::uint32_t triangle;  // for its gain, computed for the few taken (and on a tie of the two above)
  };
  // The centroid's expected gain in rays made good (good_rays.hpp).
  const auto gain = [&](const Ranked& r) {
    const std::size_t t = r.triangle;
    return probability[r.column] * triangulation.area_px2(t) * off_plane_share(triangulation.non_planarity_sigmas(t));
  };
  std::vector<Ranked> ranked;
  for (std::size_t t = 0; t < triangulation.triangles.size(); ++t) {
    const ColumnIndex c = triangulation.centroid_column(t);
    // Any observable ray (NaN: not observable), negative improvement too: a depth transition is where
    // the paper re-acquires. The return probability discounts silent regions; the improvement's size is
    // not used (in the ablation of the block refinement it ranked worse than geometry alone).
    if (!unasked[c] || std::isnan(score[c])) continue;
    const double non_planarity = triangulation.non_planarity_sigmas(t), area = triangulation.area_px2(t);
    const double priority = area * std::min(non_planarity, cap_sigmas) * probability[c];
    if (priority > 0) ranked.push_back({priority, c, static_cast<std::uint32_t>(t)});
  }
  // In the order of a full sort, sorted a stretch at a time (twice the rays still missing: two small
  // triangles may share a centroid pixel): a dense map has ~2 triangles per sample, a shot takes a few
  // thousand.
  // Ties by column, then by gain (two triangles of one centroid pixel and of one capped priority may
  // differ in it), so that the order does not depend on the triangles' numbering.
  const auto before = [&](const Ranked& a, const Ranked& b) {
    if (a.priority != b.priority) return a.priority > b.priority;
    return a.column != b.column ? a.column < b.column : gain(a) > gain(b);
  };
  TriangleRefinement refinement;
  std::vector<ColumnIndex>& out = refinement.columns;
  for (std::size_t i = 0, sorted_end = 0; i < ranked.size() && out.size() < left; ++i) {
    if (i == sorted_end) {
      sorted_end = std::min(ranked.size(), i + 2 * (left - out.size()));
      const auto first = ranked.begin() + static_cast<std::ptrdiff_t>(i), last = ranked.begin() + static_cast<std::ptrdiff_t>(sorted_end);
      std::nth_element(first, last - 1, ranked.end(), before);  // linear; a heap's partial sort was not
      std::sort(first, last, before);
    }
    const ColumnIndex c = ranked[i].column;
    if (!unasked[c]) continue;  // two small triangles may share a centroid pixel
    unasked[c] = 0;
    out.push_back(c);
    refinement.centroid_gain.push_back(gain(ranked[i]));
  }
  // Once the triangles are a pixel or two (about half the rays measured) their centroids fall on their
  // own vertices: the rest of the shot goes to the unasked rays of highest score, spread as a jittered
  // grid (fill_by_score; so does the first shot, which has no triangles), so that a shot stays full and
  // measures new rays; once every ray has been asked, to the asked ones of highest score (a second
  // measurement settles a ray's depth).
  fill_by_score(score, unasked, surface.width, left, out);
  std::vector<std::uint8_t> not_in_shot = eligible;
  for (ColumnIndex c : out) not_in_shot[c] = 0;
  fill_by_score(score, not_in_shot, surface.width, left, out);
  return refinement;
}

// The expected gain of a triangles shot in rays made good, per ray taken by the rules of good_rays.hpp;
// shot[first_centroid + i] is the centroid of gain centroid_gain[i].
double good_ray_gain(const std::vector<ColumnIndex>& shot, std::size_t first_centroid,
                     const std::vector<double>& centroid_gain, const ImprovementPyramid& pyramid, int coverage_level,
                     const std::vector<float>& probability, const std::vector<float>& block_return_rate,
                     const ReturnRecord& returns) {
  std::vector<std::uint32_t> shot_rays_in_block(pyramid.block_count(coverage_level), 0);
  for (ColumnIndex c : shot) ++shot_rays_in_block[pyramid.block_of_column(coverage_level, c)];
  double gain = 0;
  for (std::size_t i = 0; i < shot.size(); ++i) {
    const ColumnIndex c = shot[i];
    const bool centroid = i >= first_centroid && i - first_centroid < centroid_gain.size();
    const std::size_t b = pyramid.block_of_column(coverage_level, c);
    const BlockSummary& block = pyramid.block_at(coverage_level, b);
    const bool measured = !returns.empty() && returns.returned()[c] > 0;
    if (block.samples == 0)  // p as the coverage pass has it: a silent region's rays keep an optimistic prior
      gain += probability[c] * block_return_rate[b] * within_two_sigma(1) * block.observable_rays / shot_rays_in_block[b];
    else if (centroid)
      gain += centroid_gain[i - first_centroid];
    else if (!measured)
      gain += probability[c] * (within_two_sigma(1) - within_two_sigma(3));
  }
  return gain;
}

double per_ray(double gain, std::size_t rays) { return rays ? gain / static_cast<double>(rays) : 0.0; }

// Score = improvement x return probability, but for rays whose returns did not settle them: improvement
// still at or above kUnsettledImprovement after R >= 2 returns of their own (no data is 0.324; a ray seen
// once ~0.14 with kinect_v1 and ~0.19 with a VLP-16's rings, twice 0.07-0.14). Their returns are evidence
// that the next will not settle them either: a depth edge's foreground ray, whose own peak its background
// neighbours' free space carves away at every insertion, or a return beyond the grid's range, which leaves
// only free space; with the paper preset's uniform bins, also the moire's rays (about half of those seen
// 2-3 times stay at 0.2-0.32 whatever their returns: CONVENTIONS 7). Each unsettling return counts against the ray as a silence does in the return model,
// s / (s + R) (s: prior_strength_shots): without it, capture0004's 37 edge rays were asked in every shot
// of the second pass (24 times each).
constexpr float kUnsettledImprovement = 0.2f;
std::vector<float> scores_of(const ImprovementMap& improvement, const std::vector<float>& probability,
                             const ReturnRecord& returns, const ReturnModelParams& params) {
  std::vector<float> score(probability.size());
  if (returns.empty()) {
    for (std::size_t c = 0; c < score.size(); ++c) score[c] = probability[c] * improvement.value[c];
    return score;
  }
  const auto s = static_cast<float>(params.prior_strength_shots);
  const std::uint32_t* returned = returns.returned().data();
  for (std::size_t c = 0; c < score.size(); ++c) {
    score[c] = probability[c] * improvement.value[c];
    if (returned[c] >= 2 && improvement.value[c] >= kUnsettledImprovement)  // a branch: no division per ray
      score[c] *= s / (s + static_cast<float>(returned[c]));
  }
  return score;
}

Shot coarse_to_fine_shot(const ImprovementMap& improvement, const ImprovementPyramid& pyramid, const SurfaceMap* surface,
                         const SensorModel& model, const ReturnRecord& returns, const PlanRequest& request,
                         SampleTriangulator* memory) {
  const std::vector<float> probability = return_probability_map(returns, request.return_model);
  const std::vector<float> score = scores_of(improvement, probability, returns, request.return_model);
  const std::uint8_t* mask = request.candidates.empty() ? nullptr : request.candidates.data();
  const auto budget = static_cast<std::size_t>(request.budget_rays);
  Shot shot;
  // 1. Coverage: blocks without a sample, one jittered ray each, spread over the view by rank_key.
  const int coverage_level = ImprovementPyramid::level_of_block_size(request.coverage_block_columns);
  const BlockBest blocks = best_ray_per_block(pyramid, coverage_level, score, mask, returns);
  {
    const std::vector<ColumnIndex>& best = blocks.column;
    std::vector<std::pair<std::uint64_t, std::size_t>> open;  // (rank_key over the block index, block)
    for (std::size_t b = 0; b < best.size(); ++b) {
      const ColumnIndex c = best[b];
      if (c == kNoColumn || !(score[c] > 0) || probability[c] * blocks.return_rate[b] < kCoverageMinReturn) continue;
      if (pyramid.block_at(coverage_level, b).samples == 0) open.push_back({rank_key(score[c], static_cast<ColumnIndex>(b)), b});
    }
    std::sort(open.begin(), open.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
    for (std::size_t i = 0; i < open.size() && shot.columns.size() < budget; ++i) shot.columns.push_back(best[open[i].second]);
  }
  const std::size_t coverage_rays = shot.columns.size();
  // 2. Refinement with the rays left.
  const std::size_t left = budget - coverage_rays;
  TriangleRefinement triangles;
  if (left > 0) {
    std::vector<std::uint8_t> eligible = mask ? request.candidates : std::vector<std::uint8_t>(score.size(), 1);
    for (ColumnIndex c : shot.columns) eligible[c] = 0;
    if (request.refine_by == RefineBy::triangles) {
      triangles = refine_by_triangles(*surface, model, score, probability, eligible, returns, request.residual_cap_sigmas,
                                      left, memory);
      shot.columns.insert(shot.columns.end(), triangles.columns.begin(), triangles.columns.end());
    } else {
      const std::vector<ColumnIndex> refined =
          refine_by_blocks(pyramid, model, score, probability, eligible, shot.columns, returns, request, left);
      shot.columns.insert(shot.columns.end(), refined.begin(), refined.end());
    }
  }
  shot.ranked_rays = shot.columns.size();
  // 3. Expected gain: the taken rays' scores; under triangles, in rays made good (good_rays.hpp): a
  // centroid lies between samples whose OPDFs already inform it (improvement ~0.1), while what it adds is
  // to the linear prediction (measured: calibration r 0.18-0.26 with the improvement of the best rays left,
  // docs/SELECTIVE.md). The stop reads the mean score of the view's best stop_view_share, whatever the
  // shot's size: with the centroids' scores the plan stopped at 0.05-0.1 frames; with the best `budget`
  // rays left, 1 % shots stopped 13-20 % after the knee (the fewer rays, the higher their mean), 20 % shots
  // within 8 % (docs/SELECTIVE.md "Gain in rays, and the stop").
  if (request.refine_by == RefineBy::triangles) {
    shot.expected_gain = good_ray_gain(shot.columns, coverage_rays, triangles.centroid_gain, pyramid, coverage_level,
                                       probability, blocks.return_rate, returns);
    shot.stop_gain_per_ray = mean_of_best_share(score, mask, request.stop_view_share);
  } else {
    for (ColumnIndex c : shot.columns) shot.expected_gain += score[c];
    shot.stop_gain_per_ray = per_ray(shot.expected_gain, shot.ranked_rays);
  }
  return shot;
}
}  // namespace

void PlanRequest::validate(int grid_width, int grid_height) const {
  const double columns = static_cast<double>(grid_width) * grid_height;
  detail::require_parameter(budget_rays > 0 && budget_rays <= columns, "budget_rays", budget_rays,
                            "in [1, the grid's column count]");
  detail::require_parameter(negative_share >= 0 && negative_share < 1, "negative_share", negative_share, "in [0, 1)");
  detail::require_parameter(std::isfinite(stop_gain_per_ray_below) && stop_gain_per_ray_below >= 0,
                            "stop_gain_per_ray_below", stop_gain_per_ray_below, "finite and >= 0");
  detail::require_parameter(stop_view_share > 0 && stop_view_share <= 1, "stop_view_share", stop_view_share, "in (0, 1]");
  return_model.validate();
  // Enums set from numbers (Python's ShotShape(9) planned as decimation): only the named values.
  detail::require_parameter(shape == ShotShape::rays || shape == ShotShape::window || shape == ShotShape::decimation ||
                                shape == ShotShape::coarse_to_fine,
                            "shape", static_cast<double>(shape), "rays (0), window (1), decimation (2) or coarse_to_fine (3)");
  detail::require_parameter(refine_by == RefineBy::improvement || refine_by == RefineBy::residual ||
                                refine_by == RefineBy::both || refine_by == RefineBy::triangles,
                            "refine_by", static_cast<double>(refine_by),
                            "improvement (0), residual (1), both (2) or triangles (3)");
  detail::require_parameter(local_model == LocalModel::constant || local_model == LocalModel::plane, "local_model",
                            static_cast<double>(local_model), "constant (0) or plane (1)");
  if (shape == ShotShape::coarse_to_fine) {
    ImprovementPyramid::level_of_block_size(coverage_block_columns);  // InvalidParameter naming the value
    detail::require_parameter(std::isfinite(residual_cap_sigmas) && residual_cap_sigmas > 0, "residual_cap_sigmas",
                              residual_cap_sigmas, "finite and > 0");
  }
  if (shape == ShotShape::window) {
    detail::require_parameter(window_width_columns > 0 && window_width_columns <= grid_width, "window_width_columns",
                              window_width_columns, "in [1, the grid's width]");
    detail::require_parameter(window_height_columns > 0 && window_height_columns <= grid_height,
                              "window_height_columns", window_height_columns, "in [1, the grid's height]");
    detail::require_parameter(static_cast<double>(window_width_columns) * window_height_columns <= budget_rays,
                              "window_width_columns * window_height_columns",
                              static_cast<double>(window_width_columns) * window_height_columns, "<= budget_rays");
  }
  if (!candidates.empty())
    require_shape("candidate mask", ColumnShape::of_arrays(grid_width, grid_height, {candidates.size()}));
}

std::vector<float> shot_scores(const ImprovementMap& improvement, const ReturnRecord& returns,
                               const ReturnModelParams& params) {
  require_shape("return record", returns.shape(), "the improvement map", improvement.shape());
  return scores_of(improvement, return_probability_map(returns, params), returns, params);
}

namespace {
Shot decide_stop(Shot shot, const PlanRequest& request) {
  shot.stop = shot.ranked_rays == 0 || shot.stop_gain_per_ray < request.stop_gain_per_ray_below;
  const bool by_view = request.shape == ShotShape::coarse_to_fine && request.refine_by == RefineBy::triangles;
  std::ostringstream reason;
  const bool no_candidate = shot.ranked_rays == 0 && !request.candidates.empty() &&  // a pass only for an empty shot
                            std::none_of(request.candidates.begin(), request.candidates.end(), [](std::uint8_t f) { return f != 0; });
  if (no_candidate) {
    shot.reason = "no candidate ray: the candidate mask leaves none";
    return shot;
  }
  if (by_view)
    reason << "mean score of the best " << request.stop_view_share << " of the view's rays ";
  else
    reason << "expected gain " << shot.expected_gain << " over " << shot.ranked_rays << " rays, ";
  reason << shot.stop_gain_per_ray << " per ray, " << (shot.stop ? "is below " : "reaches ") << request.stop_gain_per_ray_below;
  shot.reason = reason.str();
  return shot;
}
}  // namespace

Shot plan_next_shot(const ImprovementMap& improvement, const ReturnRecord& returns, const PlanRequest& request) {
  returns.check_matches(improvement.width, improvement.height);  // first: a wrong record explains a bad budget too
  request.validate(improvement.width, improvement.height);
  if (request.shape == ShotShape::coarse_to_fine)
    throw InvalidParameter("shape coarse_to_fine needs the multi-scale pyramid: call plan_next_shot with the mapper "
                           "or with the pyramid and the sensor model");
  std::vector<float> score = shot_scores(improvement, returns, request.return_model);
  // The mask holds for every shape: a window or pattern gains nothing from rays outside it, nor takes them
  // (the rays shape ranks candidates only). They took them, and counted them as rays of the shot.
  const bool masked_block = !request.candidates.empty() && request.shape != ShotShape::rays;
  if (masked_block)
    for (std::size_t c = 0; c < score.size(); ++c)
      if (!request.candidates[c]) score[c] = std::numeric_limits<float>::quiet_NaN();
  Shot shot = request.shape == ShotShape::rays     ? rays_shot(score, request)
              : request.shape == ShotShape::window ? window_shot(score, improvement.width, improvement.height, request)
                                                   : decimation_shot(score, improvement.width, improvement.height, request);
  if (masked_block)
    shot.columns.erase(std::remove_if(shot.columns.begin(), shot.columns.end(),
                                      [&](ColumnIndex c) { return !request.candidates[c]; }),
                       shot.columns.end());
  if (request.shape != ShotShape::rays) shot.ranked_rays = shot.columns.size();
  shot.stop_gain_per_ray = per_ray(shot.expected_gain, shot.ranked_rays);
  return decide_stop(std::move(shot), request);
}

namespace {
// coarse_to_fine with the surface its triangle refinement reads (nullptr: none given) and the triangulation
// it extends (nullptr: one for this call).
Shot plan_coarse_to_fine(const ImprovementMap& improvement, const ImprovementPyramid& pyramid, const SurfaceMap* surface,
                         const SensorModel& model, const ReturnRecord& returns, const PlanRequest& request,
                         SampleTriangulator* memory = nullptr) {
  request.validate(improvement.width, improvement.height);
  require_shape("multi-scale pyramid", pyramid.shape(), "the improvement map", improvement.shape());
  require_shape("return record", returns.shape(), "the improvement map", improvement.shape());
  if (request.refine_by == RefineBy::triangles && !surface)
    throw InvalidParameter("refine_by triangles triangulates the map's surface: call plan_next_shot with the mapper");
  return decide_stop(coarse_to_fine_shot(improvement, pyramid, surface, model, returns, request, memory), request);
}
}  // namespace

Shot plan_next_shot(const ImprovementMap& improvement, const ImprovementPyramid& pyramid, const SensorModel& model,
                    const ReturnRecord& returns, const PlanRequest& request) {
  if (request.shape != ShotShape::coarse_to_fine) return plan_next_shot(improvement, returns, request);
  return plan_coarse_to_fine(improvement, pyramid, nullptr, model, returns, request);
}

Shot plan_next_shot(const Mapper& mapper, const ReturnRecord& returns, const PlanRequest& request) {
  if (request.shape != ShotShape::coarse_to_fine) return plan_next_shot(mapper.improvement(), returns, request);
  return plan_coarse_to_fine(mapper.improvement(), mapper.pyramid(), &mapper.surface(), mapper.model(), returns, request);
}

Shot plan_next_shot(const Mapper& mapper, const ReturnRecord& returns, const PlanRequest& request, PlanMemory& memory) {
  if (request.shape != ShotShape::coarse_to_fine) return plan_next_shot(mapper.improvement(), returns, request);
  return plan_coarse_to_fine(mapper.improvement(), mapper.pyramid(), &mapper.surface(), mapper.model(), returns, request,
                             &memory.triangulation);
}

int decimation_step(int width, int height, int budget_rays) {
  require_column_grid_size(width, height);
  detail::require_parameter(budget_rays > 0, "budget_rays", budget_rays, "> 0");
  const auto rays_at = [&](long long step) { return ((width + step - 1) / step) * ((height + step - 1) / step); };
  // The rays fall as the step grows, to 1 at the larger side: the smallest step within the budget by bisection.
  long long low = 1, high = std::max(width, height);
  while (low < high) {
    const long long mid = low + (high - low) / 2;
    if (rays_at(mid) > budget_rays) low = mid + 1; else high = mid;
  }
  return static_cast<int>(low);
}

std::vector<ColumnIndex> decimation_pattern(int width, int height, int step, int offset_x, int offset_y) {
  require_column_grid_size(width, height);
  detail::require_parameter(step > 0, "step", step, "> 0");
  detail::require_parameter(offset_x >= 0 && offset_x < step, "offset_x", offset_x, "in [0, step)");
  detail::require_parameter(offset_y >= 0 && offset_y < step, "offset_y", offset_y, "in [0, step)");
  std::vector<ColumnIndex> out;
  for (int y = offset_y; y < height; y += step)
    for (int x = offset_x; x < width; x += step)
      out.push_back(static_cast<ColumnIndex>(y) * static_cast<ColumnIndex>(width) + static_cast<ColumnIndex>(x));
  return out;
}

}  // namespace occ_improve
