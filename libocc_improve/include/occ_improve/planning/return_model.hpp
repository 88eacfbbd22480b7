#pragma once
// Which rays return data. Rays on dark or specular surfaces, in a projector's shadow or out of range
// never return, yet keep the no-data improvement forever and would top every plan. The record counts,
// per column, the shots that asked for the ray and the shots that got a return; the return model turns
// that into a return probability that discounts the ray's expected improvement (planner.hpp).
//
// Return probability of column j (Beta-Bernoulli, docs/SELECTIVE.md "Return model"):
//   m_j = (R_n + 1) / (A_n + 1)     prior mean from the 8 neighbours (R_n returns of A_n asks) with one
//                                   optimistic pseudo-return: 1 where nothing nearby was asked or all of it
//                                   returned, falling fast in a silent neighbourhood (a dark poster, a
//                                   shadow band, a cropped or out-of-range background)
//   p_j = (s m_j + R_j) / (s + A_j) posterior mean with s = prior_strength_shots pseudo-shots (R_j returns
//                                   of A_j asks of the ray itself)
// so a ray asked once without a return in a silent neighbourhood falls to ~0.1, one that returned stays 1,
// and a ray that returned every time stays 1. The prior is from the neighbours only, not from the view's
// overall return rate: a view with a large silent background (mOSD's cropped walls, five_people's far
// room) would otherwise discount every unseen ray, also those on the returning objects. Neighbours never
// raise the prior above 1 - the value of a ray nothing is known about - so a plan does not prefer unseen
// rays next to seen ones and bunch its rays instead of spreading them.
#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/maps/column_map.hpp"

#include <cstdint>
#include <vector>

namespace occ_improve {

/// Per column: the shots that asked for the ray and those that got a return, with the sums over each
/// column's 8 neighbours kept as shots are added (so the probability map is one pass, whatever the record).
class ReturnRecord {
public:
  ReturnRecord() = default;
  /// An empty record for a grid of width x height columns (InvalidParameter when not positive).
  static ReturnRecord for_grid(int width, int height);
  /// At most this many asks of one ray in a record from counts: the sums over 8 neighbours stay below 2^31.
  static constexpr std::uint32_t kMaxAsks = std::uint32_t{1} << 28;
  /// A record from saved counts (map_io), in one pass over the columns. Throws InvalidInput naming the
  /// value when the arrays do not hold width x height counts, a column has more returns than asks, or
  /// more than kMaxAsks asks.
  static ReturnRecord from_counts(int width, int height, std::vector<std::uint32_t> asked,
                                  std::vector<std::uint32_t> returned);

  int width() const { return width_; }
  int height() const { return height_; }
  std::size_t size() const { return asked_.size(); }
  bool empty() const { return total_asked_ == 0; }
  const std::vector<std::uint32_t>& asked() const { return asked_; }
  const std::vector<std::uint32_t>& returned() const { return returned_; }
  const std::vector<std::uint32_t>& asked_nearby() const { return asked_nearby_; }  ///< over the 8 neighbours
  const std::vector<std::uint32_t>& returned_nearby() const { return returned_nearby_; }
  std::uint64_t total_asked() const { return total_asked_; }
  std::uint64_t total_returned() const { return total_returned_; }
  ColumnShape shape() const { return ColumnShape::of_arrays(width_, height_, {asked_.size(), returned_.size()}); }

  /// Throws InvalidInput naming both sizes when the record is not one of a grid_width x grid_height grid.
  void check_matches(int grid_width, int grid_height) const;

  /// Adds one shot: got_return[i] says whether the ray columns[i] returned. A column may appear more
  /// than once (each is one ask). Everything is checked before anything is counted (nothing
  /// half-updated): InvalidInput when the sizes differ, InvalidParameter naming a column outside the grid.
  void record_shot(const std::vector<ColumnIndex>& columns, const std::vector<std::uint8_t>& got_return);

private:
  void count(ColumnIndex column, bool got_return);
  int width_ = 0, height_ = 0;
  std::vector<std::uint32_t> asked_, returned_, asked_nearby_, returned_nearby_;
  std::uint64_t total_asked_ = 0, total_returned_ = 0;
};

struct ReturnModelParams {
  double prior_strength_shots = 2.0;  ///< s: weight of the neighbourhood prior, in shots
  void validate() const;              ///< s finite and > 0, else InvalidParameter
};

/// The record's overall return rate, returns / asks (1 for an empty record): for reports.
double record_return_rate(const ReturnRecord& record);

/// p_j above, for every column (row-major, like the improvement map).
std::vector<float> return_probability_map(const ReturnRecord& record, const ReturnModelParams& params = {});

}  // namespace occ_improve
