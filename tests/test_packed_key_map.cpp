// PackedKeyMap: the open-addressing table behind the coarse grid and the
// pipeline's cell indexes, checked against std::unordered_map.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <unordered_map>

#include "semioctree/octomap_ext/packed_key_map.h"

namespace semioctree {
namespace {

TEST(PackedKeyMap, AgreesWithUnorderedMapThroughGrowth) {
  PackedKeyMap<std::uint32_t> map;  // starts empty: every slot comes from growth
  std::unordered_map<std::uint64_t, std::uint32_t> want;
  std::mt19937_64 rng(7);
  // Packed-key-like values, many repeated: both new keys and hits.
  std::uniform_int_distribution<std::uint64_t> cell(0, 50000);
  for (std::uint32_t i = 0; i < 200000; ++i) {
    const std::uint64_t key = (cell(rng) << 32) | (cell(rng) & 0xff);
    const auto got = map.try_emplace(key, i);
    const auto ref = want.try_emplace(key, i);
    ASSERT_EQ(got.second, ref.second);
    ASSERT_EQ(*got.first, ref.first->second);
  }
  EXPECT_EQ(map.size(), want.size());
  for (const auto& [key, value] : want) ASSERT_EQ(map.value_or(key, ~0u), value);
  EXPECT_EQ(map.find(~std::uint64_t(1)), nullptr);
  EXPECT_EQ(map.value_or(std::uint64_t(60000) << 32, 123u), 123u);
  // Never fuller than its bound (75 % by default), so a miss ends at an empty slot.
  EXPECT_LE(100 * map.size(), 75 * map.capacity());
}

// slots_for and bytes_for tell, without a table, what reserve gives one.
TEST(PackedKeyMap, SlotsForIsWhatReserveGives) {
  for (std::size_t n : {1u, 48u, 49u, 1000u, 786432u, 786433u}) {
    PackedKeyMap<std::uint8_t> table;
    table.reserve(n);
    EXPECT_EQ(table.capacity(), PackedKeyMap<std::uint8_t>::slots_for(n)) << n;
    EXPECT_EQ(table.memory_bytes(), PackedKeyMap<std::uint8_t>::bytes_for(n)) << n;
  }
  // At most 75 % full: 48 keys fit 64 slots, 49 need 128; 786 432 fit 2^20, one more 2^21.
  EXPECT_EQ(PackedKeyMap<std::uint8_t>::slots_for(48), 64u);
  EXPECT_EQ(PackedKeyMap<std::uint8_t>::slots_for(49), 128u);
  EXPECT_EQ(PackedKeyMap<std::uint8_t>::slots_for(786432), std::size_t(1) << 20);
  EXPECT_EQ(PackedKeyMap<std::uint8_t>::bytes_for(786433), (std::size_t(1) << 21) * 9);
}

TEST(PackedKeyMap, InsertOrAssignReplacesAndInsertIsASet) {
  int a = 0, b = 0;
  PackedKeyMap<int*, 50> nodes;
  nodes.insert_or_assign(42, &a);
  nodes.insert_or_assign(42, &b);
  EXPECT_EQ(nodes.size(), 1u);
  EXPECT_EQ(nodes.value_or(42, nullptr), &b);
  EXPECT_EQ(nodes.value_or(43, nullptr), nullptr);
  nodes.clear();
  EXPECT_EQ(nodes.size(), 0u);
  EXPECT_EQ(nodes.find(42), nullptr);

  nodes.insert_or_assign(42, &a);  // usable again after clear()
  EXPECT_EQ(nodes.value_or(42, nullptr), &a);

  PackedKeyMap<std::uint32_t> set(10);
  const std::size_t reserved = set.capacity();
  EXPECT_TRUE(set.insert(5));
  EXPECT_FALSE(set.insert(5));
  EXPECT_TRUE(set.insert(0));  // key 0 is a key like any other
  EXPECT_EQ(set.size(), 2u);
  for (std::uint64_t k = 100; k < 100 + 4 * reserved; ++k) EXPECT_TRUE(set.insert(k));
  EXPECT_GT(set.capacity(), reserved);  // grew past what was reserved, keeping every key
  EXPECT_FALSE(set.insert(5));
  EXPECT_FALSE(set.insert(0));
  EXPECT_EQ(set.size(), 2 + 4 * reserved);

  // forget_keys empties the table but keeps its slots; it fills again as new.
  const std::size_t grown = set.capacity();
  set.forget_keys();
  EXPECT_EQ(set.size(), 0u);
  EXPECT_EQ(set.capacity(), grown);
  EXPECT_EQ(set.find(5), nullptr);
  EXPECT_EQ(set.find(100), nullptr);
  EXPECT_TRUE(set.insert(100));
  EXPECT_EQ(*set.try_emplace(7, 3).first, 3u);
  EXPECT_EQ(set.size(), 2u);
}

// A lookup of a key already there never grows the table: pointers into it
// stay valid, even when the table is full up to its bound.
TEST(PackedKeyMap, FindingAnExistingKeyDoesNotMoveValues) {
  PackedKeyMap<std::uint32_t> map;
  std::uint64_t k = 0;
  while (100 * (map.size() + 1) <= 75 * std::max<std::size_t>(map.capacity(), 1) || map.size() == 0)
    map.try_emplace(k++, 7);
  const std::size_t capacity = map.capacity();
  const std::uint32_t* first = map.find(0);
  const auto again = map.try_emplace(0, 9);
  EXPECT_FALSE(again.second);
  EXPECT_EQ(again.first, first);
  EXPECT_EQ(*again.first, 7u);
  EXPECT_EQ(map.capacity(), capacity);
}

// RecentKeys answers with the value last remembered with a key while no other key has
// taken its slot, and never for a key it was not given: so a loop that remembers what its
// table holds may ask it first. Checked against the keys and values last remembered.
TEST(RecentKeys, AnswersOnlyForKeysRememberedWithTheirLastValue) {
  RecentKeys<std::uint32_t, 6> recent;                    // 64 slots: many keys share one
  std::unordered_map<std::uint64_t, std::uint32_t> last;  // key → value last remembered
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<std::uint64_t> cell(0, 300);
  std::size_t answered = 0, forgotten = 0;
  for (std::uint32_t i = 0; i < 100000; ++i) {
    const std::uint64_t key = cell(rng) * 0x100000001ull;
    if (const std::uint32_t* v = recent.find(key)) {
      ++answered;
      const auto it = last.find(key);
      ASSERT_NE(it, last.end()) << key;  // never an answer for a key not given
      ASSERT_EQ(*v, it->second) << key;  // the value given last
    } else {
      forgotten += last.count(key);  // given once, its slot since taken by another key
    }
    if (rng() % 3 == 0) {
      recent.remember(key, i);
      last[key] = i;
      ASSERT_NE(recent.find(key), nullptr);
      ASSERT_EQ(*recent.find(key), i);
    }
  }
  EXPECT_GT(answered, 1000u);
  EXPECT_GT(forgotten, 1000u);  // 301 keys in 64 slots: most answers are forgotten
  recent.forget_all();
  for (const auto& kv : last) EXPECT_EQ(recent.find(kv.first), nullptr);
}

}  // namespace
}  // namespace semioctree
