#include <gtest/gtest.h>

#include "go_feap/common/grid.h"

using go_feap::common::Aabb;
using go_feap::common::GridGeometry;
using go_feap::common::Index3;
using go_feap::common::Vec3;

TEST(GridGeometry, CoveringSnapsToResolutionMultiples) {
  const GridGeometry g = GridGeometry::covering({Vec3(-1.03, 0.0, 0.26), Vec3(2.0, 1.0, 1.0)}, 0.1);
  EXPECT_NEAR(g.origin().x(), -1.1, 1e-9);
  EXPECT_NEAR(g.origin().z(), 0.2, 1e-9);
  EXPECT_EQ(g.dims(), Index3(31, 10, 8));
}

TEST(GridGeometry, IndexCoordRoundTrip) {
  const GridGeometry g(Vec3(-2.0, -1.0, 0.0), 0.1, Index3(40, 20, 10));
  for (std::size_t l = 0; l < g.size(); l += 37) {
    const Index3 idx = g.unlinear(l);
    EXPECT_EQ(g.linear(idx), l);
    EXPECT_EQ(g.coordToIndex(g.indexToCoord(idx)), idx);
  }
  EXPECT_FALSE(g.inside(g.coordToIndex(Vec3(-2.01, 0, 0.5))));
  EXPECT_TRUE(g.inside(g.coordToIndex(Vec3(-2.0, 0, 0.5))));
}

TEST(GridGeometry, CentreRangeHoldsExactlyTheCentresInsideTheBox) {
  const GridGeometry g(Vec3(0, 0, 0), 0.1, Index3(20, 20, 20));
  const Aabb box{Vec3(0.3, 0.25, 0.0), Vec3(1.0, 0.55, 2.5)};
  Index3 lo, hi;
  g.centreRange(box, lo, hi);
  for (int a = 0; a < 3; ++a) {
    for (int i = 0; i < g.dims()[a]; ++i) {
      Index3 idx = Index3::Zero();
      idx[a] = i;
      const double c = g.indexToCoord(idx)[a];
      const bool in = c >= box.min[a] - 1e-9 && c <= box.max[a] + 1e-9;
      EXPECT_EQ(in, i >= lo[a] && i < hi[a]) << "axis " << a << " index " << i;
    }
  }
}
