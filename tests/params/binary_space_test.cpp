#include "combabc/params/binary_space.hpp"

#include <gtest/gtest.h>

#include "combabc/core/error.hpp"

namespace combabc {
namespace {

TEST(BinarySpace, IndependentMapsBitsToFreeParameters) {
  for (int d : {1, 2, 36, 1024}) {
    const auto space = BinarySpace::Independent(d, 0.3);
    EXPECT_EQ(space.dimension(), d);
    EXPECT_EQ(space.num_free(), d);
    for (int k = 0; k < d; ++k) EXPECT_EQ(space.free_of_bit(k), k);
    EXPECT_DOUBLE_EQ(space.free_prior_one()[static_cast<std::size_t>(d - 1)], 0.3);
  }
}

TEST(BinarySpace, ZeroBitsIsAnEmptySpace) {
  const auto space = BinarySpace::Independent(0);
  EXPECT_EQ(space.dimension(), 0);
  EXPECT_EQ(space.num_free(), 0);
  EXPECT_TRUE(space.bit_prior_one().empty());
  std::vector<std::uint8_t> free, bits;
  space.Expand(free, bits);
  EXPECT_TRUE(space.Reduce(bits, free));
}

TEST(BinarySpace, TiedBitsShareOneFreeParameterWithConditionedPrior) {
  BinarySpaceOptions o;
  o.dimension = 5;
  o.prior_one = {0.5, 0.2, 0.5, 0.6, 0.5};
  o.tied = {{1, 3}};
  const BinarySpace space(o);
  EXPECT_EQ(space.num_free(), 4);
  EXPECT_EQ(space.free_of_bit(1), space.free_of_bit(3));
  // P(both 1 | equal) = 0.2*0.6 / (0.2*0.6 + 0.8*0.4)
  EXPECT_NEAR(space.free_prior_one()[static_cast<std::size_t>(space.free_of_bit(1))],
              0.12 / (0.12 + 0.32),
              1e-15);
  const std::vector<std::uint8_t> free = {1, 0, 1, 1};
  std::vector<std::uint8_t> bits(5);
  space.Expand(free, bits);
  EXPECT_EQ(bits, (std::vector<std::uint8_t>{1, 0, 1, 0, 1}));
  std::vector<std::uint8_t> back(4);
  EXPECT_TRUE(space.Reduce(bits, back));
  EXPECT_EQ(back, free);
  bits[3] = 1;  // violates the tie
  EXPECT_FALSE(space.Reduce(bits, back));
}

TEST(BinarySpace, InvalidOptionsNameTheField) {
  auto why_of = [](const BinarySpaceOptions& o) {
    std::string why;
    EXPECT_FALSE(o.IsValid(&why));
    return why;
  };
  BinarySpaceOptions o;
  o.dimension = -1;
  EXPECT_EQ(why_of(o), "BinarySpaceOptions::dimension = -1; must be >= 0");
  o.dimension = 3;
  o.prior_one = {0.5, 0.5};
  EXPECT_NE(why_of(o).find("prior_one has 2 entries"), std::string::npos);
  o.prior_one = {0.5, 1.5, 0.5};
  EXPECT_NE(why_of(o).find("prior_one[1] = 1.5"), std::string::npos);
  o.prior_one.clear();
  o.tied = {{0, 3}};
  EXPECT_NE(why_of(o).find("tied[0] contains bit 3"), std::string::npos);
  o.tied = {{0, 1}, {1, 2}};
  EXPECT_NE(why_of(o).find("groups must be disjoint"), std::string::npos);
  o.tied = {{0}};
  EXPECT_NE(why_of(o).find("fewer than 2"), std::string::npos);
  EXPECT_THROW(BinarySpace{o}, Error);
}

}  // namespace
}  // namespace combabc
