#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include "yarf/support/wavefront.h"

namespace yarf {
namespace {

// GroupBy's contract, written the plain way: groups in order of their
// key's first appearance, each with its indices in ascending order.
std::vector<std::pair<uint32_t, std::vector<uint32_t>>> GroupedOneByOne(const std::vector<uint32_t>& keys) {
  std::vector<std::pair<uint32_t, std::vector<uint32_t>>> groups;
  std::map<uint32_t, size_t> group_of;
  for (uint32_t i = 0; i < keys.size(); ++i) {
    const auto [it, added] = group_of.try_emplace(keys[i], groups.size());
    if (added) groups.push_back({keys[i], {}});
    groups[it->second].second.push_back(i);
  }
  return groups;
}

TEST(GroupBy, KeepsItsContractWithOneKeyFewOrMany) {
  std::mt19937 random(7);
  // One key throughout (the shortcut), a few (linear search), many (the
  // hash map), and a batch whose last key alone differs.
  for (const uint32_t distinct : {1u, 3u, 16u, 17u, 200u})
    for (const size_t size : {1u, 2u, 15u, 1000u}) {
      std::vector<uint32_t> keys(size);
      for (uint32_t& key : keys) key = 1000 + random() % distinct;
      EXPECT_EQ(GroupBy(keys), GroupedOneByOne(keys)) << distinct << " keys, " << size << " indices";
      keys.back() = 5;
      EXPECT_EQ(GroupBy(keys), GroupedOneByOne(keys)) << distinct << " keys, " << size << " indices, last apart";
    }
  EXPECT_TRUE(GroupBy(std::vector<uint32_t>{}).empty());
}

}  // namespace
}  // namespace yarf
