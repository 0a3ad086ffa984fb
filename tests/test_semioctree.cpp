// SemiOcTree: node layout, coarse grid alignment, octant edits, pruning,
// statistics, compaction and the .ot round trip.
#include <gtest/gtest.h>
#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <sstream>
#include <tuple>
#include <type_traits>

#include "semioctree/octomap_ext/node_stream.h"
#include "semioctree/octomap_ext/semioctree.h"

namespace semioctree {
namespace {

using OctantId = std::tuple<unsigned, unsigned, unsigned, unsigned>;  // key xyz, level

using OctantData = std::tuple<Label, float, std::uint16_t>;  // label, log-odds, aux

std::map<OctantId, OctantData> octant_map(const SemiOcTree& t) {
  std::map<OctantId, OctantData> m;
  t.for_each_octant([&](const Octant& o) {
    m[{o.key.k[0], o.key.k[1], o.key.k[2], o.level}] =
        std::make_tuple(o.label(), o.node->getLogOdds(), o.node->aux());
  });
  return m;
}

// The coarse index (a hash map) must agree with the tree itself: every octant
// octant_map found by walking from the root is found again through the index,
// and the index holds exactly the coarse nodes the tree walk hands over.
void expect_index_agrees(const SemiOcTree& t, const std::map<OctantId, OctantData>& m) {
  for (const auto& [id, value] : m) {
    const auto& [x, y, z, level] = id;
    const auto o = t.find_octant(octomap::OcTreeKey(x, y, z));
    ASSERT_TRUE(o) << "no octant at key " << x << " " << y << " " << z;
    EXPECT_EQ(o->level, level) << "key " << x << " " << y << " " << z;
    EXPECT_EQ(o->label(), std::get<0>(value)) << "key " << x << " " << y << " " << z;
    EXPECT_EQ(o->node->getLogOdds(), std::get<1>(value));
    EXPECT_EQ(o->node->aux(), std::get<2>(value));
  }
  std::size_t coarse = 0;
  t.for_each_coarse([&](const CoarseIndex& c, const SemiOcTreeNode* node) {
    ++coarse;
    EXPECT_EQ(t.find_coarse(c), node) << "coarse " << c.x << " " << c.y << " " << c.z;
  });
  EXPECT_EQ(coarse, t.coarse_count());
}

octomap::OcTreeKey key_at(const SemiOcTree& t, double x, double y, double z) {
  octomap::OcTreeKey k;
  EXPECT_TRUE(t.key_of({x, y, z}, k));
  return k;
}

TEST(SemiOcTreeNode, IsSixteenBytesAndKeepsLabel) {
  EXPECT_EQ(sizeof(SemiOcTreeNode), 16u);
  SemiOcTreeNode n;
  EXPECT_EQ(n.label(), Label::kUnknown);
  n.set_label(Label::kWindow);
  n.set_aux(513);
  n.set_flag(SemiOcTreeNode::kCoarseRoot, true);
  n.set_flag(SemiOcTreeNode::kMarked, true);
  SemiOcTreeNode m;
  m.copyData(n);
  EXPECT_EQ(m.label(), Label::kWindow);
  EXPECT_EQ(m.aux(), 513);
  // The flags are the tree's own bookkeeping of this node: not copied.
  EXPECT_FALSE(m.has_flag(SemiOcTreeNode::kCoarseRoot));
  EXPECT_FALSE(m.has_flag(SemiOcTreeNode::kMarked));
  EXPECT_TRUE(m == n);
  m.set_label(Label::kDoor);
  EXPECT_FALSE(m == n);
}

TEST(SemiOcTree, ValidatesLeafAndCoarseSize) {
  EXPECT_EQ(SemiOcTree(0.05, 0.8).leaf_level(), 4u);
  EXPECT_EQ(SemiOcTree(0.05, 0.8).leaf_level(), 4u);  // the leaves' level, k
  EXPECT_EQ(SemiOcTree(0.05, 0.05).leaf_level(), 0u);
  EXPECT_EQ(SemiOcTree(0.1, 0.8).leaf_level(), 3u);
  try {
    SemiOcTree bad(0.05, 0.7);
    FAIL() << "0.7 is not 0.05 times a power of two";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("power of two"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("0.7"), std::string::npos) << e.what();
  }
  EXPECT_THROW(SemiOcTree(0.0, 0.8), std::invalid_argument);
  EXPECT_THROW(SemiOcTree(-0.05, 0.8), std::invalid_argument);
  EXPECT_THROW(SemiOcTree(0.05, std::nan("")), std::invalid_argument);
  EXPECT_THROW(SemiOcTree(0.05, 0.025), std::invalid_argument);  // coarse below leaf
  // Octant sizes from the coarse voxel (level 0) to the leaf (level k), none finer.
  const SemiOcTree t(0.05, 0.8);
  EXPECT_DOUBLE_EQ(t.octant_size(0), 0.8);
  EXPECT_DOUBLE_EQ(t.octant_size(3), 0.1);
  EXPECT_DOUBLE_EQ(t.octant_size(4), 0.05);
  EXPECT_THROW(t.octant_size(5), std::out_of_range);
}

// Coarse voxel (i, j, l) is [iL, (i+1)L)³, whatever the point's sign.
TEST(SemiOcTree, CoarseGridIsAlignedToTheWorld) {
  for (const auto& [leaf, coarse] : {std::pair{0.05, 0.8}, std::pair{0.125, 1.0}}) {
    SemiOcTree t(leaf, coarse);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-20.0, 20.0);
    std::uniform_int_distribution<int> cell(-25, 25);
    for (int n = 0; n < 20000; ++n) {
      Point3 p(u(rng), u(rng), u(rng));
      if (n % 3 == 0) p = {cell(rng) * coarse, cell(rng) * coarse, cell(rng) * coarse};  // on faces
      if (n % 3 == 1) p.x = cell(rng) * coarse;
      CoarseIndex c;
      ASSERT_TRUE(t.coarse_index_of(p, c));
      // Consistent with the leaf key. Leaf cell j = key − 2^15 is [j r, (j+1) r)
      // (OctoMap's key origin) and a coarse voxel spans 2^k leaf cells, so on
      // every axis i = floor(j / 2^k), and coarse_key(c), the voxel's
      // min-corner key, is 2^15 + i·2^k: the first leaf cell of the voxel.
      octomap::OcTreeKey key;
      ASSERT_TRUE(t.key_of(p, key));
      const int cells = 1 << t.leaf_level();
      const octomap::OcTreeKey ck = t.coarse_key(c);
      for (int a = 0; a < 3; ++a) {
        const int ci = a == 0 ? c.x : (a == 1 ? c.y : c.z);
        const int j = int(leaf_cell(key.k[a]));
        const int floor_div = j >= 0 ? j / cells : -((-j + cells - 1) / cells);
        EXPECT_EQ(ci, floor_div) << "axis " << a << " key " << key.k[a];
        EXPECT_EQ(int(ck.k[a]), kKeyOrigin + ci * cells) << "axis " << a;
        // The min-corner cell starts at iL.
        EXPECT_NEAR(t.keyToCoord(ck.k[a]) - 0.5 * leaf, ci * coarse, 1e-9) << "axis " << a;
      }
      EXPECT_EQ(t.coarse_index(ck), c);
      // The point lies in [iL, (i+1)L); exact when L is exact in binary.
      const double tol = (coarse == 1.0) ? 0.0 : 1e-9;
      for (int a = 0; a < 3; ++a) {
        const int ci = a == 0 ? c.x : (a == 1 ? c.y : c.z);
        EXPECT_GE(p[a], ci * coarse - tol) << "axis " << a << " p " << p[a];
        EXPECT_LT(p[a], (ci + 1) * coarse + tol) << "axis " << a << " p " << p[a];
        if (coarse == 1.0) {
          EXPECT_EQ(ci, int(std::floor(p[a])));
        }
      }
      // The coarse voxel's min corner maps back to the same index.
      CoarseIndex back;
      ASSERT_TRUE(t.coarse_index_of(t.coarse_min_corner(c), back));
      if (coarse == 1.0) {
        EXPECT_EQ(back, c);
      }
    }
  }
}

TEST(SemiOcTree, CoarseVoxelsOfTwoTreesCoincide) {
  SemiOcTree a(0.05, 0.8), b(0.05, 0.8);
  a.create_coarse({-3, 2, -1});
  b.create_coarse({5, 5, 5});
  b.create_coarse({-3, 2, -1});
  CoarseIndex ca, cb;
  ASSERT_TRUE(a.coarse_index_of({-2.0, 1.7, -0.1}, ca));
  ASSERT_TRUE(b.coarse_index_of({-2.0, 1.7, -0.1}, cb));
  EXPECT_EQ(ca, cb);
  EXPECT_EQ(ca, (CoarseIndex{-3, 2, -1}));
  EXPECT_NE(a.find_coarse(ca), nullptr);
  EXPECT_NE(b.find_coarse(cb), nullptr);
  EXPECT_EQ(a.coarse_count(), 1u);
  EXPECT_EQ(b.coarse_count(), 2u);
}

TEST(SemiOcTree, SetLabelAtAnyLevelAndSplit) {
  SemiOcTree t(0.05, 0.8);  // k = 4
  const auto key = key_at(t, 0.33, 0.41, 0.07);
  t.set_label(key, 0, Label::kEmpty);
  auto o = t.find_octant(key);
  ASSERT_TRUE(o);
  EXPECT_EQ(o->level, 0u);
  EXPECT_DOUBLE_EQ(o->size, 0.8);
  EXPECT_EQ(o->label(), Label::kEmpty);
  EXPECT_NEAR(o->center.x, 0.4, 1e-12);

  t.split(key, 0);  // children inherit the label
  o = t.find_octant(key);
  ASSERT_TRUE(o);
  EXPECT_EQ(o->level, 1u);
  EXPECT_EQ(o->label(), Label::kEmpty);
  EXPECT_EQ(t.statistics().at_level(1), 8u);

  t.set_label(key, 4, Label::kOccupied);  // a leaf: splits levels 1..3 on the way
  o = t.find_octant(key);
  ASSERT_TRUE(o);
  EXPECT_EQ(o->level, 4u);
  EXPECT_DOUBLE_EQ(o->size, 0.05);
  EXPECT_EQ(o->label(), Label::kOccupied);
  EXPECT_TRUE(t.isNodeOccupied(o->node));
  const auto st = t.statistics();
  EXPECT_EQ(st.total(), 8u + 7u + 7u + 7u);  // 7 siblings at levels 1..3, 8 leaves
  EXPECT_EQ(st.count[4][int(Label::kOccupied)], 1u);
  EXPECT_EQ(st.count[4][int(Label::kEmpty)], 7u);
  EXPECT_NEAR(st.volume[int(Label::kOccupied)], 0.05 * 0.05 * 0.05, 1e-15);
  EXPECT_NEAR(st.total_volume(), 0.8 * 0.8 * 0.8, 1e-12);

  // Labelling the coarse voxel again makes it one octant: children removed.
  const std::size_t before = t.size();
  t.set_label(key, 0, Label::kOccluded);
  EXPECT_EQ(t.statistics().total(), 1u);
  EXPECT_EQ(t.size(), before - 8u * 4u);
  EXPECT_EQ(t.size(), t.calcNumNodes());
  EXPECT_THROW(t.split(key, 4), std::logic_error);
}

TEST(SemiOcTree, PruneMergesOnlySameLabelsAndKeepsCoarseVoxels) {
  SemiOcTree t(0.1, 0.8);  // k = 3
  // 8 coarse voxels forming a 2×2×2 block, all empty and unsplit: OctoMap would
  // merge them into their parent; we must not.
  for (int x = 0; x < 2; ++x)
    for (int y = 0; y < 2; ++y)
      for (int z = 0; z < 2; ++z) t.create_coarse({x, y, z}, Label::kEmpty);
  // One coarse voxel split into 8 same-label children: merges back.
  const auto k1 = key_at(t, 0.1, 0.1, 0.1);
  t.split(k1, 0);
  // Another split with one different child: stays split.
  const auto k2 = key_at(t, 0.9, 0.1, 0.1);
  t.split(k2, 0);
  t.set_label(k2, 1, Label::kOccluded);
  t.prune();
  EXPECT_EQ(t.coarse_count(), 8u);
  const auto st = t.statistics();
  EXPECT_EQ(st.at_level(0), 7u);
  EXPECT_EQ(st.at_level(1), 8u);
  EXPECT_EQ(st.count[1][int(Label::kOccluded)], 1u);
  for (int x = 0; x < 2; ++x)
    for (int y = 0; y < 2; ++y)
      for (int z = 0; z < 2; ++z) EXPECT_NE(t.find_coarse({x, y, z}), nullptr);
  // The index still points at live nodes: a traversal sees every voxel.
  int steps = 0, split_steps = 0;
  t.traverse({0.05, 0.1, 0.1}, {1.5, 1.3, 1.1}, [&](const RayStep& s) {
    EXPECT_NE(s.node, nullptr);
    ++steps;
    split_steps += s.level == 1;
    return true;
  });
  EXPECT_GE(steps, 4);
  EXPECT_GE(split_steps, 1);  // passes through the voxel that stayed split
  EXPECT_EQ(t.size(), t.calcNumNodes());
}

TEST(SemiOcTree, CompactKeepsEveryOctant) {
  SemiOcTree t(0.05, 0.4);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> lvl(0, 3), lab(0, kLabelCount - 1);
  for (int i = 0; i < 300; ++i)
    t.set_label(key_at(t, u(rng), u(rng), u(rng)), lvl(rng), Label(lab(rng)));
  const auto before = octant_map(t);
  t.compact();
  EXPECT_EQ(octant_map(t), before);
  // compact() moves every node: the coarse index must point at the new ones.
  expect_index_agrees(t, before);
  EXPECT_EQ(t.size(), t.calcNumNodes());
  const auto o = t.find_octant(Point3(0.01, 0.01, 0.01));
  ASSERT_TRUE(o);
  EXPECT_EQ(t.find_coarse(t.coarse_index(o->key)) != nullptr, true);
}

TEST(SemiOcTree, OtRoundTripIsLossless) {
  // 1/30 m: a resolution the .ot header's 6 digits cannot hold exactly.
  SemiOcTree t(1.0 / 30.0, 8.0 / 30.0);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  std::uniform_int_distribution<int> lvl(0, 3), lab(0, kLabelCount - 1), aux(0, 65535);
  for (int i = 0; i < 500; ++i) {
    SemiOcTreeNode* n = t.set_label(key_at(t, u(rng), u(rng), u(rng)), lvl(rng), Label(lab(rng)));
    n->set_aux(std::uint16_t(aux(rng)));
  }
  std::stringstream buf;
  ASSERT_TRUE(t.write(buf));
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(buf));
  ASSERT_TRUE(read);
  auto* back = dynamic_cast<SemiOcTree*>(read.get());
  ASSERT_NE(back, nullptr) << "AbstractOcTree::read must create a SemiOcTree";
  EXPECT_EQ(back->getResolution(), t.getResolution());  // exact, not 6 digits
  EXPECT_EQ(back->leaf_level(), t.leaf_level());
  EXPECT_EQ(back->coarse_count(), t.coarse_count());
  EXPECT_EQ(back->size(), t.size());
  const auto original = octant_map(t);
  EXPECT_EQ(octant_map(*back), original);
  // The coarse index is rebuilt on reading.
  expect_index_agrees(*back, original);
}

// Files written before the node flags kSeen and kBoundary were dropped may
// hold them in each node's reserved byte: such a file still loads, the same.
TEST(SemiOcTree, ReadsFilesWithTheOldNodeFlags) {
  SemiOcTree t(0.05, 0.4);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> lvl(0, 3), lab(0, kLabelCount - 1);
  for (int i = 0; i < 200; ++i)
    t.set_label(key_at(t, u(rng), u(rng), u(rng)), lvl(rng), Label(lab(rng)));
  std::stringstream buf;
  t.writeData(buf);
  std::string data = buf.str();
  // Payload header: 48 bytes, the node stream's FNV-1a hash in its last 8. Each
  // node: 8 bytes of data (the reserved byte at 5), then its child mask.
  constexpr std::size_t kHeader = 48, kRecord = SemiOcTreeNode::kSerializedBytes + 1;
  ASSERT_EQ((data.size() - kHeader) % kRecord, 0u);
  for (std::size_t at = kHeader; at < data.size(); at += kRecord)
    data[at + 5] = char((at / kRecord) % 2 ? 0x06 : 0x02);  // kSeen | kBoundary, kSeen
  const std::uint64_t hash = fnv1a64(data.data() + kHeader, data.size() - kHeader);
  std::memcpy(&data[kHeader - 8], &hash, 8);
  std::istringstream in(data);
  SemiOcTree back(0.05);
  ASSERT_NO_THROW(back.readData(in));
  const auto original = octant_map(t);
  EXPECT_EQ(octant_map(back), original);
  expect_index_agrees(back, original);
  // Written again, the reserved bytes are 0: the file of the original tree.
  std::stringstream again;
  back.writeData(again);
  EXPECT_EQ(again.str(), buf.str());
}

TEST(SemiOcTree, ReadDataRejectsCorruptPayload) {
  SemiOcTree t(0.05, 0.8);
  t.set_label(key_at(t, 0.1, 0.2, 0.3), 2, Label::kOccluded);
  std::stringstream buf;
  t.writeData(buf);
  std::string data = buf.str();
  data[data.size() - 3] ^= 0x10;  // a byte inside the node stream
  std::istringstream in(data);
  SemiOcTree back(0.05);
  EXPECT_THROW(back.readData(in), FileFormatError);
  EXPECT_EQ(back.size(), 0u);
  std::istringstream truncated(buf.str().substr(0, 30));
  EXPECT_THROW(back.readData(truncated), FileFormatError);
}

// OctoMap's own edits bypass the labels and the coarse index: updateNode would
// change log-odds under an unchanged label, or create a coarse voxel the index
// never hears of; deleteNode would free an indexed node. They must be refused.
template <class T, class = void>
struct HasDeleteNode : std::false_type {};
template <class T>
struct HasDeleteNode<T, std::void_t<decltype(std::declval<T&>().deleteNode(
                            std::declval<const octomap::OcTreeKey&>(), 0u))>> : std::true_type {};
template <class T, class = void>
struct HasSwapContent : std::false_type {};
template <class T>
struct HasSwapContent<T, std::void_t<decltype(std::declval<T&>().swapContent(std::declval<T&>()))>>
    : std::true_type {};
static_assert(HasDeleteNode<octomap::OcTree>::value && HasSwapContent<octomap::OcTree>::value,
              "the detectors must see OctoMap's own functions");
template <class T, class = void>
struct HasReadBinary : std::false_type {};
template <class T>
struct HasReadBinary<
    T, std::void_t<decltype(std::declval<T&>().readBinary(std::declval<std::istream&>()))>>
    : std::true_type {};
template <class T, class = void>
struct HasWriteBinary : std::false_type {};
template <class T>
struct HasWriteBinary<
    T, std::void_t<decltype(std::declval<T&>().writeBinary(std::declval<const std::string&>()))>>
    : std::true_type {};
static_assert(HasReadBinary<octomap::OcTree>::value && HasWriteBinary<octomap::OcTree>::value,
              "the detectors must see OctoMap's own functions");
static_assert(!HasReadBinary<SemiOcTree>::value && !HasWriteBinary<SemiOcTree>::value,
              ".bt holds no labels: refused before anything is touched");
static_assert(!HasDeleteNode<SemiOcTree>::value, "deleteNode would free indexed coarse voxels");
static_assert(!HasSwapContent<SemiOcTree>::value, "swapContent would leave both indexes stale");

TEST(SemiOcTree, RefusesOctoMapOccupancyUpdates) {
  SemiOcTree t(0.1, 0.8);
  t.set_label(key_at(t, 0.05, 0.05, 0.05), 3, Label::kOccupied);
  t.create_coarse({1, 0, 0}, Label::kEmpty);
  const auto before = octant_map(t);
  const std::size_t nodes = t.size();
  octomap::AbstractOccupancyOcTree& abstract = t;
  octomap::OccupancyOcTreeBase<SemiOcTreeNode>& base = t;
  const octomap::point3d inside(0.95f, 0.05f, 0.05f), outside(5.0f, 5.0f, 0.5f);
  const octomap::OcTreeKey key = key_at(t, 0.95, 0.05, 0.05);
  EXPECT_THROW(abstract.updateNode(inside, true), std::logic_error);
  EXPECT_THROW(abstract.updateNode(key, 0.85f), std::logic_error);
  EXPECT_THROW(abstract.updateNode(key, false), std::logic_error);
  EXPECT_THROW(abstract.updateNode(inside, -0.4f), std::logic_error);
  EXPECT_THROW(base.updateNode(5.0, 5.0, 0.5, true), std::logic_error);
  EXPECT_THROW(base.updateNode(5.0, 5.0, 0.5, 0.85f), std::logic_error);
  EXPECT_THROW(base.setNodeValue(key, 3.5f), std::logic_error);
  EXPECT_THROW(base.setNodeValue(inside, 3.5f), std::logic_error);
  EXPECT_THROW(base.setNodeValue(0.95, 0.05, 0.05, 3.5f), std::logic_error);
  octomap::Pointcloud cloud;
  cloud.push_back(outside);
  EXPECT_THROW(base.insertPointCloud(cloud, inside), std::logic_error);
  EXPECT_THROW(base.insertPointCloud(cloud, inside, octomap::pose6d()), std::logic_error);
  EXPECT_THROW(base.insertPointCloud(
                   octomap::ScanNode(new octomap::Pointcloud(cloud), octomap::pose6d(), 0)),
               std::logic_error);
  EXPECT_THROW(base.insertPointCloudRays(cloud, inside), std::logic_error);
  EXPECT_THROW(base.insertRay(inside, outside), std::logic_error);
  EXPECT_EQ(t.size(), nodes);
  EXPECT_EQ(octant_map(t), before);
  expect_index_agrees(t, before);

  // The .bt format holds occupancy only. Writing one would first make every
  // unknown or occluded octant's value occupied (toMaxLikelihood).
  std::stringstream out;
  EXPECT_THROW(abstract.writeBinaryConst(out), std::logic_error);
  EXPECT_THROW(abstract.writeBinary(out), std::logic_error);
  EXPECT_THROW(base.toMaxLikelihood(), std::logic_error);
  EXPECT_EQ(octant_map(t), before);
  // Reading one through a base class: OctoMap's reader clears the tree and
  // takes the file's resolution before the data, so the tree ends up empty at
  // that resolution, and consistent.
  octomap::OcTree plain(0.05);
  plain.updateNode(outside, true);
  std::stringstream bt;
  ASSERT_TRUE(plain.writeBinary(bt));
  try {
    const bool read = abstract.readBinary(bt);
    ADD_FAILURE() << "readBinary returned " << read << " instead of throwing";
  } catch (const std::logic_error&) {
  }
  EXPECT_EQ(t.size(), 0u);
  EXPECT_EQ(t.coarse_count(), 0u);
  EXPECT_DOUBLE_EQ(t.leaf_size(), 0.05);
  EXPECT_EQ(t.size(), t.calcNumNodes());
}

}  // namespace
}  // namespace semioctree
