#include <gtest/gtest.h>

#include <random>

#include "relaxed_connectivity/io/lzf.h"

namespace rc {
namespace {

std::vector<uint8_t> roundTrip(const std::vector<uint8_t>& data, size_t* compressed_size) {
  const std::vector<uint8_t> packed = lzfCompress(data.data(), data.size());
  *compressed_size = packed.size();
  EXPECT_LE(packed.size(), data.size() + data.size() / 32 + 1);
  std::vector<uint8_t> out(data.size());
  std::string error;
  const size_t produced = lzfDecompress(packed.data(), packed.size(), out.data(), out.size(), &error);
  EXPECT_TRUE(error.empty()) << error;
  EXPECT_EQ(produced, data.size());
  return out;
}

TEST(Lzf, RandomDataRoundTripsAndBarelyExpands) {
  std::mt19937 rng(1);
  for (size_t size : {0u, 1u, 2u, 3u, 31u, 32u, 33u, 1000u, 100000u}) {
    std::vector<uint8_t> data(size);
    for (auto& b : data) b = static_cast<uint8_t>(rng());
    size_t packed = 0;
    EXPECT_EQ(roundTrip(data, &packed), data) << "size " << size;
    EXPECT_LE(packed, size + size / 32 + 1);
  }
}

TEST(Lzf, RepetitiveDataRoundTripsAndShrinks) {
  std::mt19937 rng(2);
  // long runs (matches up to the 264-byte maximum and overlapping copies), short periods, far repeats
  std::vector<uint8_t> data;
  data.insert(data.end(), 5000, 0xAB);
  for (int k = 0; k < 3000; ++k) data.push_back(static_cast<uint8_t>(k % 7));
  std::vector<uint8_t> block(700);
  for (auto& b : block) b = static_cast<uint8_t>(rng());
  for (int k = 0; k < 20; ++k) data.insert(data.end(), block.begin(), block.end());
  for (int k = 0; k < 50000; ++k) data.push_back(static_cast<uint8_t>((rng() % 4) * 60));
  size_t packed = 0;
  EXPECT_EQ(roundTrip(data, &packed), data);
  EXPECT_LT(packed, data.size() / 2);

  std::vector<uint8_t> zeros(1 << 20, 0);
  EXPECT_EQ(roundTrip(zeros, &packed), zeros);
  EXPECT_LT(packed, zeros.size() * 3 / 250);  // 264-byte matches cost 3 bytes each
}

TEST(Lzf, DecodesHandWrittenStream) {
  // literal "abc" (ctrl 2), then a back reference of length 6 at distance 3 (ctrl (6-2)<<5, offset byte 2)
  const std::vector<uint8_t> stream = {2, 'a', 'b', 'c', 4 << 5, 2};
  std::vector<uint8_t> out(9);
  std::string error;
  ASSERT_EQ(lzfDecompress(stream.data(), stream.size(), out.data(), out.size(), &error), 9u) << error;
  EXPECT_EQ(std::string(out.begin(), out.end()), "abcabcabc");
}

TEST(Lzf, CorruptStreamsAreRejected) {
  std::vector<uint8_t> out(16);
  std::string error;
  const std::vector<uint8_t> reference_before_start = {0, 'a', 1 << 5, 5};
  EXPECT_EQ(lzfDecompress(reference_before_start.data(), 4, out.data(), out.size(), &error), 0u);
  EXPECT_NE(error.find("before the start"), std::string::npos) << error;
  error.clear();
  const std::vector<uint8_t> truncated_literal = {5, 'a', 'b'};
  EXPECT_EQ(lzfDecompress(truncated_literal.data(), 3, out.data(), out.size(), &error), 0u);
  EXPECT_NE(error.find("past the end"), std::string::npos) << error;
  error.clear();
  const std::vector<uint8_t> too_long = {2, 'a', 'b', 'c', 7 << 5, 200, 2};
  EXPECT_EQ(lzfDecompress(too_long.data(), too_long.size(), out.data(), out.size(), &error), 0u);
  EXPECT_NE(error.find("more than the expected"), std::string::npos) << error;
}

}  // namespace
}  // namespace rc
