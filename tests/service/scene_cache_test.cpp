// SceneCache's budgets between tenants: a tenant within its fair share keeps its scenes however
// much another uploads; a tenant over its share gives way; a scene that cannot fit otherwise is
// refused (naming the cache) and evicts nothing. The statistics count what went.
#include "service/scene_cache.hpp"

#include <gmock/gmock.h>

#include "wire/errors.hpp"

namespace shadow::test {
namespace {

using service::SceneCache;
using ::testing::HasSubstr;
using ::testing::StartsWith;

// A scene of `units` kilobytes of positions (plus its few bytes of bookkeeping).
std::shared_ptr<const Scene> scene_of(size_t units) {
  auto scene = std::make_shared<Scene>();
  scene->meshes.emplace_back().positions.resize(units * 250);
  return scene;
}
uint64_t bytes_of(size_t units) {
  return SceneCache::bytes_of(*scene_of(units));
}

// The case, in kilobytes: 40 in all, 30 per tenant, so two tenants' quotas overlap.
SceneCache::Limits limits() {
  return {.total_bytes = 40000 + 100, .tenant_bytes = 30000 + 100};
}

TEST(SceneCacheTest, AnotherTenantFillingItsQuotaLeavesAWithinShareTenantAlone) {
  SceneCache cache(limits());
  ASSERT_TRUE(cache.put("b", "b1", scene_of(14)));
  // A fills its quota (29 of 30) in three scenes, past the total with B's: the third evicts A's
  // own oldest, A being over its share (40 / 2), not B's older one within it.
  ASSERT_TRUE(cache.put("a", "a1", scene_of(10)));
  ASSERT_TRUE(cache.put("a", "a2", scene_of(10)));
  ASSERT_TRUE(cache.put("a", "a3", scene_of(9)));
  EXPECT_NE(cache.find("b", "b1"), nullptr);
  EXPECT_EQ(cache.find("a", "a1"), nullptr);
  EXPECT_NE(cache.find("a", "a2"), nullptr);
  EXPECT_NE(cache.find("a", "a3"), nullptr);
  const std::string a = "a", b = "b";
  EXPECT_EQ(cache.usage(&b).evictions, 0u);
  EXPECT_EQ(cache.usage(&b).scenes, 1u);
  EXPECT_EQ(cache.usage(&b).bytes, bytes_of(14));
  EXPECT_EQ(cache.usage(&a).evictions, 1u);
  EXPECT_EQ(cache.usage(&a).scenes, 2u);
  EXPECT_EQ(cache.usage().evictions, 1u);
  EXPECT_EQ(cache.usage().bytes, bytes_of(14) + bytes_of(10) + bytes_of(9));
}

// One scene of A's within A's quota but over its share while B holds its own: refused, and the
// plan that would have made room (A's own older scene) is not carried out.
TEST(SceneCacheTest, ASceneThatDoesNotFitIsRefusedAndEvictsNothing) {
  SceneCache cache(limits());
  ASSERT_TRUE(cache.put("b", "b1", scene_of(14)));
  ASSERT_TRUE(cache.put("a", "a1", scene_of(5)));
  try {
    cache.put("a", "big", scene_of(29));
    ADD_FAILURE() << "a scene over the share was cached by evicting a tenant within its share";
  } catch (const ResourceExhausted& e) {
    EXPECT_EQ(e.field(), "scene_cache");
    EXPECT_THAT(e.what(), HasSubstr("--scene-cache-bytes"));
  }
  EXPECT_NE(cache.find("b", "b1"), nullptr);
  EXPECT_NE(cache.find("a", "a1"), nullptr);
  EXPECT_EQ(cache.find("a", "big"), nullptr);
  EXPECT_EQ(cache.usage().evictions, 0u);
  EXPECT_EQ(cache.usage().bytes, bytes_of(14) + bytes_of(5));
  // Once B has gone, A has the cache to itself within its quota.
  SceneCache alone(limits());
  ASSERT_TRUE(alone.put("a", "a1", scene_of(5)));
  ASSERT_TRUE(alone.put("a", "big", scene_of(29)));  // its own budget: a1 goes
  EXPECT_EQ(alone.find("a", "a1"), nullptr);
  EXPECT_EQ(alone.usage().evictions, 1u);
}

// A tenant over its share (it came first and filled its quota) gives way to a newcomer, its
// least recently used scene first and only until it is back within its share.
TEST(SceneCacheTest, ATenantOverItsShareGivesWay) {
  SceneCache cache(limits());
  ASSERT_TRUE(cache.put("c", "c1", scene_of(9)));
  ASSERT_TRUE(cache.put("c", "c2", scene_of(9)));
  ASSERT_TRUE(cache.put("c", "c3", scene_of(9)));
  ASSERT_NE(cache.find("c", "c1"), nullptr);  // c1 is now the most recently used
  ASSERT_TRUE(cache.put("d", "d1", scene_of(15)));
  EXPECT_EQ(cache.find("c", "c2"), nullptr);
  EXPECT_NE(cache.find("c", "c1"), nullptr);
  EXPECT_NE(cache.find("c", "c3"), nullptr);
  EXPECT_NE(cache.find("d", "d1"), nullptr);
  const std::string c = "c", d = "d";
  EXPECT_EQ(cache.usage(&c).evictions, 1u);
  EXPECT_EQ(cache.usage(&c).bytes, 2 * bytes_of(9));
  EXPECT_EQ(cache.usage(&d).evictions, 0u);
  // Both are within their share (20) now: D's scene over it is refused, and neither D's own
  // older scene nor C's goes for it.
  EXPECT_THROW(cache.put("d", "d2", scene_of(25)), ResourceExhausted);
  EXPECT_NE(cache.find("d", "d1"), nullptr);
  EXPECT_EQ(cache.usage().evictions, 1u);
  EXPECT_EQ(cache.usage().scenes, 3u);
}

// With one tenant (no tokens) the cache is the plain LRU it always was.
TEST(SceneCacheTest, OneTenantIsLeastRecentlyUsedFirstOut) {
  SceneCache cache({.total_bytes = 2 * bytes_of(10)});
  ASSERT_TRUE(cache.put("", "1", scene_of(10)));
  ASSERT_TRUE(cache.put("", "2", scene_of(10)));
  ASSERT_NE(cache.find("", "1"), nullptr);
  ASSERT_TRUE(cache.put("", "3", scene_of(10)));
  EXPECT_EQ(cache.find("", "2"), nullptr);
  EXPECT_NE(cache.find("", "1"), nullptr);
  EXPECT_FALSE(cache.put("", "3", scene_of(10)));  // held already
  EXPECT_EQ(cache.usage().evictions, 1u);
  EXPECT_THAT(
      [&] {
        try {
          cache.check_fits(3 * bytes_of(10), "total_bytes");
        } catch (const ResourceExhausted& e) {
          return std::string(e.what());
        }
        return std::string();
      }(),
      StartsWith("total_bytes: "));
}

}  // namespace
}  // namespace shadow::test
