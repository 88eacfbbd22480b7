// The return record and its Beta-Bernoulli return probability.
#include "occ_improve/errors.hpp"
#include "occ_improve/planning/return_model.hpp"

#include <gtest/gtest.h>


namespace occ_improve {
namespace {

TEST(ReturnModel, EmptyRecordDiscountsNothing) {
  const ReturnRecord r = ReturnRecord::for_grid(5, 4);
  EXPECT_TRUE(r.empty());
  EXPECT_DOUBLE_EQ(record_return_rate(r), 1.0);
  for (float p : return_probability_map(r)) EXPECT_FLOAT_EQ(p, 1.0f);
}

TEST(ReturnModel, PosteriorFollowsTheDocumentedFormula) {
  ReturnRecord r = ReturnRecord::for_grid(5, 5);
  const ColumnIndex centre = 12, right = 13, far = 0;
  r.record_shot({centre, centre, right}, {0, 0, 1});
  EXPECT_EQ(r.asked()[centre], 2u);
  EXPECT_EQ(r.returned()[right], 1u);
  EXPECT_DOUBLE_EQ(record_return_rate(r), 1.0 / 3.0);
  const auto p = return_probability_map(r);  // s = 2
  const double prior_centre = (1.0 + 1.0) / (1.0 + 1.0);  // neighbour `right`: 1 return of 1 ask
  EXPECT_NEAR(p[centre], 2.0 * prior_centre / (2.0 + 2.0), 1e-6);
  const double prior_right = (0.0 + 1.0) / (2.0 + 1.0);  // neighbour `centre`: 0 of 2
  EXPECT_NEAR(p[right], (2.0 * prior_right + 1.0) / (2.0 + 1.0), 1e-6);
  EXPECT_FLOAT_EQ(p[far], 1.0f);                           // nothing asked around it
  const ColumnIndex beside_centre = 11;                    // neighbours: centre (0 of 2)
  EXPECT_NEAR(p[beside_centre], 1.0 / 3.0, 1e-6);          // unasked, silent neighbourhood
  EXPECT_LT(p[centre], p[right]);
}

TEST(ReturnModel, BadShotsChangeNothing) {
  ReturnRecord r = ReturnRecord::for_grid(4, 4);
  r.record_shot({1, 2}, {1, 1});
  const ReturnRecord before = r;
  try {
    r.record_shot({3, 16}, {1, 0});
    FAIL() << "no throw";
  } catch (const InvalidParameter& e) {
    EXPECT_NE(std::string(e.what()).find("shot column = 16"), std::string::npos);
  }
  EXPECT_THROW(r.record_shot({3}, {1, 0}), InvalidInput);
  EXPECT_EQ(r.asked(), before.asked());
  EXPECT_EQ(r.returned(), before.returned());
  EXPECT_EQ(r.asked_nearby(), before.asked_nearby());
  EXPECT_EQ(r.total_asked(), before.total_asked());
  EXPECT_THROW(ReturnRecord::for_grid(0, 4), InvalidParameter);
  ReturnModelParams bad;
  bad.prior_strength_shots = 0;
  EXPECT_THROW(return_probability_map(r, bad), InvalidParameter);
}

TEST(ReturnModel, MismatchedAndInconsistentRecordsAreNamed) {
  ReturnRecord r = ReturnRecord::for_grid(4, 4);
  EXPECT_NO_THROW(r.check_matches(4, 4));
  EXPECT_THROW(r.check_matches(4, 5), InvalidInput);
  std::vector<std::uint32_t> asked(16, 0), returned(16, 0);
  returned[3] = 1;
  try {
    ReturnRecord::from_counts(4, 4, asked, returned);
    FAIL() << "no throw";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("column 3"), std::string::npos);
  }
  EXPECT_THROW(ReturnRecord::from_counts(4, 4, std::vector<std::uint32_t>(15, 0), returned), InvalidInput);
}

// Large counts cost nothing (replaying each ask took a minute for 2^32 asks, a map file's claim) and are
// bounded so that the sums over 8 neighbours fit: 2^28 asks in every column, each sum 8 x 2^28 = 2^31.
TEST(ReturnModel, FromCountsTakesLargeCountsAtOnceAndRefusesMoreThanTwoToThe28) {
  const std::uint32_t most = ReturnRecord::kMaxAsks;
  const ReturnRecord r = ReturnRecord::from_counts(3, 3, std::vector<std::uint32_t>(9, most), std::vector<std::uint32_t>(9, 1));
  EXPECT_EQ(r.asked_nearby()[4], 8u * most);
  EXPECT_EQ(r.asked_nearby()[0], 3u * most);
  EXPECT_EQ(r.returned_nearby()[4], 8u);
  EXPECT_EQ(r.total_asked(), 9ull * most);
  std::vector<std::uint32_t> asked(9, 1), returned(9, 0);
  asked[5] = most + 1;
  try {
    ReturnRecord::from_counts(3, 3, asked, returned);
    FAIL() << "no throw";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("column 5 has 0 returns of 268435457 asks"), std::string::npos) << e.what();
  }
}

// A record beyond 32-bit column indices is refused by name (Python saw MemoryError for 100000 x 100000).
// (One below that which cannot be allocated is a ResourceLimit; not tested: with overcommit the zeroing
// is what fails, as an out-of-memory kill.)
TEST(ReturnModel, OversizedRecordsAreTypedErrors) {
  try {
    ReturnRecord::for_grid(100000, 100000);
    FAIL() << "no throw";
  } catch (const InvalidParameter& e) {
    EXPECT_NE(std::string(e.what()).find("width x height"), std::string::npos) << e.what();
  }
}

TEST(ReturnModel, FromCountsEqualsTheShotsThatMadeThem) {
  ReturnRecord shots = ReturnRecord::for_grid(6, 5);
  shots.record_shot({0, 7, 7, 29, 14}, {1, 0, 1, 0, 0});
  shots.record_shot({7, 8, 29}, {0, 1, 0});
  const ReturnRecord loaded = ReturnRecord::from_counts(6, 5, shots.asked(), shots.returned());
  EXPECT_EQ(loaded.asked_nearby(), shots.asked_nearby());
  EXPECT_EQ(loaded.returned_nearby(), shots.returned_nearby());
  EXPECT_EQ(loaded.total_returned(), shots.total_returned());
  EXPECT_EQ(return_probability_map(loaded), return_probability_map(shots));
}

}  // namespace
}  // namespace occ_improve
