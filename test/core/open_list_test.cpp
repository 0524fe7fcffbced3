// OpenList (open_list.hpp): the guidance search's open list, lowest f first, then deepest t,
// popping equal entries in the same order as std::push_heap / std::pop_heap would.
#include "gdrhcr/open_list.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace gdrhcr {
namespace {

struct Ref {
  float f;
  int32_t t, id;
};
bool worse(const Ref& x, const Ref& y) { return x.f != y.f ? x.f > y.f : x.t < y.t; }

TEST(OpenList, PopsTheLowestFFirstAndAmongEqualFTheDeepest) {
  OpenList open;
  open.push(5.f, 1, 0);
  open.push(3.5f, 2, 1);
  open.push(3.5f, 4, 2);
  open.push(0.f, 0, 3);
  open.push(12.25f, 9, 4);
  open.push(3.5f, 3, 5);
  std::vector<int32_t> ids;
  while (!open.empty()) ids.push_back(open.pop());
  EXPECT_EQ(ids, (std::vector<int32_t>{3, 2, 5, 1, 0, 4}));
}

// Pushes and pops interleaved at random, with many entries equal in f and t: the same ids in the
// same order as the library's heap under the same order. This is what keeps the guidance's paths
// unchanged by the open list.
TEST(OpenList, PopsEqualEntriesInTheLibraryHeapsOrder) {
  std::mt19937 rng(7);
  for (int round = 0; round < 20; ++round) {
    OpenList open;
    std::vector<Ref> ref;
    int32_t next = 0;
    for (int op = 0; op < 3000; ++op) {
      if (ref.empty() || rng() % 3 != 0) {
        // Few distinct values, so ties are common; f from sums like the search's costs.
        const float f = static_cast<float>(rng() % 8) + 0.1f * static_cast<float>(rng() % 3);
        const int32_t t = static_cast<int32_t>(rng() % 5);
        open.push(f, t, next);
        ref.push_back({f, t, next});
        std::push_heap(ref.begin(), ref.end(), worse);
        ++next;
      } else {
        std::pop_heap(ref.begin(), ref.end(), worse);
        const int32_t want = ref.back().id;
        ref.pop_back();
        ASSERT_EQ(open.pop(), want) << "round " << round << ", operation " << op;
      }
      ASSERT_EQ(open.size(), ref.size());
    }
    while (!ref.empty()) {
      std::pop_heap(ref.begin(), ref.end(), worse);
      ASSERT_EQ(open.pop(), ref.back().id);
      ref.pop_back();
    }
    EXPECT_TRUE(open.empty());
  }
}

}  // namespace
}  // namespace gdrhcr
