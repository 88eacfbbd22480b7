#include "occ_improve/return_model.hpp"

#include "occ_improve/errors.hpp"

#include <cmath>
#include <sstream>
#include <string>

namespace occ_improve {
namespace {

/// out[c] = sum of in over the 3 x 3 neighbourhood of c clipped to the grid, minus in[c] itself
/// (separable: row sums, then column sums of those).
std::vector<float> neighbour_sums(const std::vector<std::uint32_t>& in, int width, int height) {
  const auto w = static_cast<std::size_t>(width);
  std::vector<float> rows(in.size()), out(in.size());
  for (std::size_t y = 0; y < static_cast<std::size_t>(height); ++y) {
    const std::uint32_t* r = &in[y * w];
    for (std::size_t x = 0; x < w; ++x)
      rows[y * w + x] = static_cast<float>(r[x]) + (x > 0 ? static_cast<float>(r[x - 1]) : 0.0f) +
                        (x + 1 < w ? static_cast<float>(r[x + 1]) : 0.0f);
  }
  for (std::size_t y = 0; y < static_cast<std::size_t>(height); ++y)
    for (std::size_t x = 0; x < w; ++x) {
      const std::size_t c = y * w + x;
      out[c] = rows[c] + (y > 0 ? rows[c - w] : 0.0f) + (y + 1 < static_cast<std::size_t>(height) ? rows[c + w] : 0.0f) -
               static_cast<float>(in[c]);
    }
  return out;
}

}  // namespace

ReturnRecord ReturnRecord::for_grid(int width, int height) {
  detail::require_parameter(width > 0, "width", width, "> 0");
  detail::require_parameter(height > 0, "height", height, "> 0");
  ReturnRecord r;
  r.width = width;
  r.height = height;
  r.asked.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), 0);
  r.returned = r.asked;
  return r;
}

void ReturnRecord::check_matches(int grid_width, int grid_height) const {
  std::ostringstream m;
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (width != grid_width || height != grid_height)
    m << "return record of " << width << " x " << height << " columns does not match the grid's " << grid_width
      << " x " << grid_height;
  else if (asked.size() != n || returned.size() != n)
    m << "return record holds " << asked.size() << " / " << returned.size() << " counts for " << n << " columns";
  if (m.tellp() != 0) throw InvalidInput(m.str());
}

void ReturnRecord::check_counts() const {
  std::ostringstream m;
  std::uint64_t a = 0, r = 0;
  for (std::size_t c = 0; c < asked.size() && m.tellp() == 0; ++c) {
    if (returned[c] > asked[c])
      m << "return record column " << c << " has " << returned[c] << " returns of " << asked[c] << " asks";
    a += asked[c];
    r += returned[c];
  }
  if (m.tellp() == 0 && (a != total_asked || r != total_returned))
    m << "return record totals " << total_asked << " / " << total_returned << " differ from the columns' sums " << a
      << " / " << r;
  if (m.tellp() != 0) throw InvalidInput(m.str());
}

void ReturnModelParams::validate() const {
  detail::require_parameter(std::isfinite(prior_strength_shots) && prior_strength_shots > 0, "prior_strength_shots",
                            prior_strength_shots, "finite and > 0");
}

void record_shot(ReturnRecord& record, const std::vector<ColumnIndex>& columns,
                 const std::vector<std::uint8_t>& got_return) {
  if (columns.size() != got_return.size())
    throw InvalidInput("record_shot: " + std::to_string(columns.size()) + " columns but " +
                       std::to_string(got_return.size()) + " return flags");
  for (ColumnIndex c : columns)
    detail::require_parameter(c < record.size(), "shot column", c, "inside the return record's grid");
  for (std::size_t i = 0; i < columns.size(); ++i) {
    ++record.asked[columns[i]];
    if (got_return[i]) ++record.returned[columns[i]];
    record.total_returned += got_return[i] ? 1 : 0;
  }
  record.total_asked += columns.size();
}

double record_return_rate(const ReturnRecord& record) {
  return (static_cast<double>(record.total_returned) + 1.0) / (static_cast<double>(record.total_asked) + 1.0);
}

std::vector<float> return_probability_map(const ReturnRecord& record, const ReturnModelParams& params) {
  params.validate();
  record.check_matches(record.width, record.height);  // sizes only: the map is computed every round
  const auto rate = static_cast<float>(record_return_rate(record));
  if (record.empty()) return std::vector<float>(record.size(), rate);
  const auto s = static_cast<float>(params.prior_strength_shots);
  const std::vector<float> asked_n = neighbour_sums(record.asked, record.width, record.height);
  const std::vector<float> returned_n = neighbour_sums(record.returned, record.width, record.height);
  std::vector<float> p(record.size());
  for (std::size_t c = 0; c < p.size(); ++c) {
    const float prior = (returned_n[c] + rate) / (asked_n[c] + 1.0f);
    p[c] = (s * prior + static_cast<float>(record.returned[c])) / (s + static_cast<float>(record.asked[c]));
  }
  return p;
}

}  // namespace occ_improve
