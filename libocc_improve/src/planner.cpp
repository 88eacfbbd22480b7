#include "occ_improve/planner.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/ranking.hpp"

#include <algorithm>
#include <cmath>
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

}  // namespace

void PlanRequest::validate(int grid_width, int grid_height) const {
  const double columns = static_cast<double>(grid_width) * grid_height;
  detail::require_parameter(budget_rays > 0 && budget_rays <= columns, "budget_rays", budget_rays,
                            "in [1, the grid's column count]");
  detail::require_parameter(negative_share >= 0 && negative_share < 1, "negative_share", negative_share, "in [0, 1)");
  detail::require_parameter(std::isfinite(stop_gain_per_ray_below) && stop_gain_per_ray_below >= 0,
                            "stop_gain_per_ray_below", stop_gain_per_ray_below, "finite and >= 0");
  return_model.validate();
  if (shape == ShotShape::window) {
    detail::require_parameter(window_width_columns > 0 && window_width_columns <= grid_width, "window_width_columns",
                              window_width_columns, "in [1, the grid's width]");
    detail::require_parameter(window_height_columns > 0 && window_height_columns <= grid_height,
                              "window_height_columns", window_height_columns, "in [1, the grid's height]");
    detail::require_parameter(static_cast<double>(window_width_columns) * window_height_columns <= budget_rays,
                              "window_width_columns * window_height_columns",
                              static_cast<double>(window_width_columns) * window_height_columns, "<= budget_rays");
  }
  if (!candidates.empty() && candidates.size() != static_cast<std::size_t>(columns)) {
    std::ostringstream m;
    m << "candidate mask of " << candidates.size() << " columns does not match the grid's " << grid_width << " x "
      << grid_height;
    throw InvalidInput(m.str());
  }
}

std::vector<float> shot_scores(const ImprovementMap& improvement, const ReturnRecord& returns,
                               const ReturnModelParams& params) {
  if (improvement.value.size() != static_cast<std::size_t>(improvement.width) * static_cast<std::size_t>(improvement.height))
    throw InvalidInput("improvement map holds " + std::to_string(improvement.value.size()) + " values for " +
                       std::to_string(improvement.width) + " x " + std::to_string(improvement.height) + " columns");
  returns.check_matches(improvement.width, improvement.height);
  std::vector<float> score = return_probability_map(returns, params);
  for (std::size_t c = 0; c < score.size(); ++c) score[c] *= improvement.value[c];
  return score;
}

Shot plan_next_shot(const ImprovementMap& improvement, const ReturnRecord& returns, const PlanRequest& request) {
  request.validate(improvement.width, improvement.height);
  const std::vector<float> score = shot_scores(improvement, returns, request.return_model);
  Shot shot = request.shape == ShotShape::rays     ? rays_shot(score, request)
              : request.shape == ShotShape::window ? window_shot(score, improvement.width, improvement.height, request)
                                                   : decimation_shot(score, improvement.width, improvement.height, request);
  if (request.shape != ShotShape::rays) shot.ranked_rays = shot.columns.size();
  const double threshold = request.stop_gain_per_ray_below * static_cast<double>(shot.ranked_rays);
  shot.stop = shot.ranked_rays == 0 || shot.expected_gain < threshold;
  std::ostringstream reason;
  reason << "expected gain " << shot.expected_gain << " over " << shot.ranked_rays << " rays "
         << (shot.stop ? "is below " : "reaches ") << threshold << " (" << request.stop_gain_per_ray_below << " per ray)";
  shot.reason = reason.str();
  return shot;
}

int decimation_step(int width, int height, int budget_rays) {
  detail::require_parameter(budget_rays > 0, "budget_rays", budget_rays, "> 0");
  int step = 1;
  while ((static_cast<long long>(width + step - 1) / step) * ((height + step - 1) / step) > budget_rays) ++step;
  return step;
}

std::vector<ColumnIndex> decimation_pattern(int width, int height, int step, int offset_x, int offset_y) {
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
