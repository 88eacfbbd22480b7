#include "occ_improve/planning/return_model.hpp"

#include "occ_improve/errors.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <new>
#include <sstream>
#include <string>

namespace occ_improve {

namespace {

/// visit(n) for the up to 8 neighbours n of column (x, y) in a width x height grid.
template <class Visit>
void for_each_neighbour(int x, int y, int width, int height, Visit&& visit) {
  for (int yy = std::max(0, y - 1); yy <= std::min(height - 1, y + 1); ++yy)
    for (int xx = std::max(0, x - 1); xx <= std::min(width - 1, x + 1); ++xx)
      if (xx != x || yy != y)
        visit(static_cast<std::size_t>(yy) * static_cast<std::size_t>(width) + static_cast<std::size_t>(xx));
}

}  // namespace

ReturnRecord ReturnRecord::for_grid(int width, int height) {
  require_column_grid_size(width, height);
  const std::uint64_t columns = static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height);
  ReturnRecord r;
  r.width_ = width;
  r.height_ = height;
  try {
    r.asked_.assign(columns, 0);
    r.returned_ = r.asked_nearby_ = r.returned_nearby_ = r.asked_;
  } catch (const std::bad_alloc&) {
    throw ResourceLimit("return record of " + std::to_string(width) + " x " + std::to_string(height) + " columns: its " +
                        std::to_string(16 * columns) + " bytes of counts could not be allocated");
  }
  return r;
}

ReturnRecord ReturnRecord::from_counts(int width, int height, std::vector<std::uint32_t> asked,
                                       std::vector<std::uint32_t> returned) {
  // The arrays' sizes first: a claimed 65535 x 65535 grid with small arrays allocated 68 GB before the check.
  require_shape("return record", ColumnShape::of_arrays(width, height, {asked.size(), returned.size()}));
  ReturnRecord r = for_grid(width, height);
  for (std::size_t c = 0; c < r.size(); ++c)
    if (returned[c] > asked[c] || asked[c] > kMaxAsks) {
      std::ostringstream m;
      m << "return record column " << c << " has " << returned[c] << " returns of " << asked[c] << " asks"
        << (asked[c] > kMaxAsks ? " (at most 2^28 asks of one ray)" : "");
      throw InvalidInput(m.str());
    }
  // The counts as they are, and their sums over each column's 8 neighbours in one pass: the same record as
  // the shots that made them (replaying every ask took as long as the counts are large: a map file
  // claiming 2^32 asks of one ray kept its loader busy for a minute, deaf to Ctrl-C).
  r.asked_ = std::move(asked);
  r.returned_ = std::move(returned);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const std::size_t c = static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x);
      r.total_asked_ += r.asked_[c];
      r.total_returned_ += r.returned_[c];
      for_each_neighbour(x, y, width, height, [&](std::size_t n) {
        r.asked_nearby_[c] += r.asked_[n];
        r.returned_nearby_[c] += r.returned_[n];
      });
    }
  return r;
}

void ReturnRecord::check_matches(int grid_width, int grid_height) const {
  require_shape("return record", shape(), "the grid", ColumnShape::of_grid(grid_width, grid_height));
}

void ReturnRecord::count(ColumnIndex column, bool got_return) {
  ++asked_[column];
  returned_[column] += got_return ? 1 : 0;
  const int x = static_cast<int>(column % static_cast<ColumnIndex>(width_));
  const int y = static_cast<int>(column / static_cast<ColumnIndex>(width_));
  for_each_neighbour(x, y, width_, height_, [&](std::size_t n) {
    ++asked_nearby_[n];
    returned_nearby_[n] += got_return ? 1 : 0;
  });
  ++total_asked_;
  total_returned_ += got_return ? 1 : 0;
}

void ReturnRecord::record_shot(const std::vector<ColumnIndex>& columns, const std::vector<std::uint8_t>& got_return) {
  if (columns.size() != got_return.size())
    throw InvalidInput("record_shot: " + std::to_string(columns.size()) + " columns but " +
                       std::to_string(got_return.size()) + " return flags");
  for (ColumnIndex c : columns) detail::require_parameter(c < size(), "shot column", c, "inside the return record's grid");
  for (std::size_t i = 0; i < columns.size(); ++i) count(columns[i], got_return[i] != 0);
}

void ReturnModelParams::validate() const {
  detail::require_parameter(std::isfinite(prior_strength_shots) && prior_strength_shots > 0, "prior_strength_shots",
                            prior_strength_shots, "finite and > 0");
}

double record_return_rate(const ReturnRecord& record) {
  return record.empty() ? 1.0 : static_cast<double>(record.total_returned()) / static_cast<double>(record.total_asked());
}

std::vector<float> return_probability_map(const ReturnRecord& record, const ReturnModelParams& params) {
  params.validate();
  std::vector<float> p(record.size(), 1.0f);
  if (record.empty()) return p;
  const auto s = static_cast<float>(params.prior_strength_shots);
  const std::uint32_t *asked = record.asked().data(), *returned = record.returned().data();
  const std::uint32_t *asked_n = record.asked_nearby().data(), *returned_n = record.returned_nearby().data();
  for (std::size_t c = 0; c < p.size(); ++c) {
    const float prior = (static_cast<float>(returned_n[c]) + 1.0f) / (static_cast<float>(asked_n[c]) + 1.0f);
    p[c] = (s * prior + static_cast<float>(returned[c])) / (s + static_cast<float>(asked[c]));
  }
  return p;
}

}  // namespace occ_improve
