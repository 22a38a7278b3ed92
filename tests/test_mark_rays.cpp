// The packet walks (AVX2, AVX-512) store exactly the bytes of the scalar walk (their oracle), which is
// traverseRayKeys(), itself checked against OctoMap in test_ray_keys.cpp.
#include "nbv/kernels/mark_rays.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <mutex>
#include <random>
#include <set>
#include <tuple>
#include <vector>

namespace {

using nbv::kernels::DenseBox;
using nbv::kernels::Index3;
using nbv::kernels::Isa;
using nbv::kernels::VoxelLattice;

struct Marked {
  std::vector<std::uint8_t> bytes;
  std::set<std::tuple<int, int, int, int>> outside;
};

using nbv::kernels::MarkSpec;
const MarkSpec kStore{MarkSpec::Mode::Store, 7};
const MarkSpec kNearest{MarkSpec::Mode::MinStepIndex, 0};

Marked mark(const std::vector<Eigen::Vector3f>& origins, const std::vector<Eigen::Vector3f>& ends,
            double res, const Index3& box_min, const Index3& box_max, Isa isa,
            const MarkSpec& spec = kStore) {
  DenseBox box = DenseBox::around(box_min, box_max);
  Marked out;
  out.bytes.assign(box.bytes(), 0);
  box.data = out.bytes.data();
  std::mutex mutex;
  nbv::kernels::markRays(origins, ends, VoxelLattice(res), box, spec,
                         [&](const Index3& k, std::uint8_t byte) {
                           std::lock_guard<std::mutex> lock(mutex);
                           out.outside.insert({k.x(), k.y(), k.z(), byte});
                         },
                         isa);
  return out;
}

/// The packet instruction sets this build and CPU have (none: the scalar path only).
std::vector<Isa> packetIsas() {
  std::vector<Isa> isas = nbv::kernels::availableIsas();
  isas.erase(isas.begin());  // Isa::Scalar
  return isas;
}

/// Scalar and every packet walk agree; stored voxels are exactly those of traverseRayKeys.
void expectAgree(const Eigen::Vector3f& origin, const std::vector<Eigen::Vector3f>& ends, double res,
                 const Index3& box_min, const Index3& box_max) {
  const Marked scalar = mark({origin}, ends, res, box_min, box_max, Isa::Scalar);
  std::set<std::tuple<int, int, int>> voxels;
  for (const auto& e : ends) {
    nbv::kernels::traverseRayKeys(origin, e, VoxelLattice(res),
                                  [&](const Index3& k) { voxels.insert({k.x(), k.y(), k.z()}); });
  }
  EXPECT_EQ(static_cast<std::size_t>(std::count(scalar.bytes.begin(), scalar.bytes.end(), 7)) +
                scalar.outside.size(),
            voxels.size());
  if (packetIsas().empty()) GTEST_SKIP() << "no AVX2 here: scalar path only";
  for (Isa isa : packetIsas()) {
    const Marked packet = mark({origin}, ends, res, box_min, box_max, isa);
    EXPECT_TRUE(packet.bytes == scalar.bytes) << nbv::kernels::isaName(isa);
    EXPECT_EQ(packet.outside, scalar.outside) << nbv::kernels::isaName(isa);
  }
}

TEST(MarkRays, RandomRaysScalarEqualsPackets) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> coord(-0.8f, 0.8f);
  const Eigen::Vector3f origin(0.013f, -0.021f, 0.05f);
  for (std::size_t count : {1u, 2u, 3u, 5u, 7u, 9u, 12u, 4099u}) {  // not multiples of the lane widths
    std::vector<Eigen::Vector3f> ends;
    for (std::size_t i = 0; i < count; ++i) ends.emplace_back(coord(rng), coord(rng), coord(rng));
    expectAgree(origin, ends, 0.01, Index3::Constant(-82), Index3::Constant(82));
  }
}

TEST(MarkRays, AxesCornersAndZeroLengthRays) {
  const Eigen::Vector3f origin(0.0f, 0.0f, 0.0f);  // a voxel corner
  std::vector<Eigen::Vector3f> ends = {{0.3f, 0.0f, 0.0f},  {0.0f, -0.3f, 0.0f}, {0.0f, 0.0f, 0.3f},
                                       {0.3f, 0.3f, 0.3f},  {-0.2f, 0.2f, 0.0f}, {0.0f, 0.0f, 0.0f},
                                       {0.004f, 0.001f, 0.002f}};  // the last two: same voxel
  for (int i = -5; i <= 5; ++i) {
    for (int j = -5; j <= 5; ++j) ends.emplace_back(0.03f * static_cast<float>(i), 0.03f * static_cast<float>(j), 0.2f);
  }
  expectAgree(origin, ends, 0.01, Index3::Constant(-40), Index3::Constant(40));
}

TEST(MarkRays, VoxelsOutsideTheBoxGoToTheSink) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> coord(-0.5f, 0.5f);
  std::vector<Eigen::Vector3f> ends;
  for (int i = 0; i < 1000; ++i) ends.emplace_back(coord(rng), coord(rng), coord(rng));
  const Eigen::Vector3f origin(0.1f, 0.1f, 0.1f);
  const Marked scalar = mark({origin}, ends, 0.01, Index3::Constant(-10), Index3::Constant(20), Isa::Scalar);
  EXPECT_FALSE(scalar.outside.empty());
  expectAgree(origin, ends, 0.01, Index3::Constant(-10), Index3::Constant(20));
}

TEST(MarkRays, NearestStepIndexAlongOneRay) {
  // From the centre of voxel 0 to voxel 5 along x: voxels 1..4 get k = 1..4, voxel 0 nothing.
  const Marked m = mark({{0.005f, 0.005f, 0.005f}}, {{0.055f, 0.005f, 0.005f}}, 0.01,
                        Index3(0, 0, 0), Index3(7, 7, 7), Isa::Scalar, kNearest);
  EXPECT_EQ(m.bytes[0], 0);
  for (int i = 1; i <= 4; ++i) EXPECT_EQ(m.bytes[static_cast<std::size_t>(i)], i);
  EXPECT_EQ(m.bytes[5], 0);
}

TEST(MarkRays, NearestStepIndexWithPerRayOriginsScalarEqualsPackets) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> coord(-0.3f, 0.3f), offset(-0.3f, 0.3f);
  std::vector<Eigen::Vector3f> origins, ends;
  for (int i = 0; i < 3001; ++i) {
    origins.emplace_back(coord(rng), coord(rng), coord(rng));
    ends.push_back(origins.back() + Eigen::Vector3f(offset(rng), offset(rng), offset(rng)));
  }
  // A box that holds most rays, so both the packet and the scalar fallback run.
  const Marked scalar = mark(origins, ends, 0.01, Index3::Constant(-50), Index3::Constant(50), Isa::Scalar, kNearest);
  EXPECT_GT(std::count_if(scalar.bytes.begin(), scalar.bytes.end(), [](std::uint8_t b) { return b > 1; }), 1000);
  EXPECT_FALSE(scalar.outside.empty());
  if (packetIsas().empty()) GTEST_SKIP() << "no AVX2 here: scalar path only";
  for (Isa isa : packetIsas()) {
    const Marked packet = mark(origins, ends, 0.01, Index3::Constant(-50), Index3::Constant(50), isa, kNearest);
    EXPECT_TRUE(packet.bytes == scalar.bytes) << nbv::kernels::isaName(isa);
    EXPECT_EQ(packet.outside, scalar.outside) << nbv::kernels::isaName(isa);
  }
}

TEST(MarkRays, EndFlagsAreTheEndVoxelsOfEveryRay) {
  std::mt19937 rng(41);
  std::uniform_real_distribution<float> coord(-0.3f, 0.3f);
  const Eigen::Vector3f origin(0.013f, -0.021f, 0.05f);
  std::vector<Eigen::Vector3f> ends = {origin, origin + Eigen::Vector3f(0.001f, 0.0f, 0.0f)};  // same voxel
  for (int i = 0; i < 2001; ++i) ends.emplace_back(coord(rng), coord(rng), coord(rng));
  const VoxelLattice lattice(0.01);
  DenseBox box = DenseBox::around(Index3::Constant(-30), Index3::Constant(29));  // ends at the faces too
  std::vector<std::uint8_t> expected(box.bytes(), 0);
  for (const auto& e : ends) {
    std::size_t at = 0;
    ASSERT_TRUE(box.locate(lattice.worldToIndex(e), at));
    expected[at] = 1;
  }
  const auto sink = [](const Index3&, std::uint8_t) {};
  for (Isa isa : nbv::kernels::availableIsas()) {
    std::vector<std::uint8_t> bytes(box.bytes(), 0), flags(box.bytes(), 0);
    box.data = bytes.data();
    MarkSpec spec = kStore;
    spec.end_flags = flags.data();
    nbv::kernels::markRays(std::span(&origin, 1), ends, lattice, box, spec, sink, isa);
    EXPECT_TRUE(flags == expected) << nbv::kernels::isaName(isa);
    // An end voxel outside the box is refused.
    const std::vector<Eigen::Vector3f> outside = {{0.5f, 0.0f, 0.0f}};
    EXPECT_THROW(nbv::kernels::markRays(std::span(&origin, 1), outside, lattice, box, spec, sink, isa),
                 std::invalid_argument);
  }
}

TEST(MarkRays, MismatchedOriginsAndTooLongNearestRaysAreRefused) {
  std::vector<std::uint8_t> bytes(512 * 8);
  DenseBox box = DenseBox::around(Index3::Zero(), Index3::Constant(15));
  box.data = bytes.data();
  const auto sink = [](const Index3&, std::uint8_t) {};
  const std::vector<Eigen::Vector3f> two = {{0.f, 0.f, 0.f}, {0.1f, 0.f, 0.f}};
  const std::vector<Eigen::Vector3f> three = {{0.f, 0.f, 0.f}, {0.1f, 0.f, 0.f}, {0.2f, 0.f, 0.f}};
  EXPECT_THROW(nbv::kernels::markRays(two, three, VoxelLattice(0.01), box, kStore, sink, Isa::Scalar),
               std::invalid_argument);
  const std::vector<Eigen::Vector3f> origin = {{0.f, 0.f, 0.f}};
  const std::vector<Eigen::Vector3f> far = {{3.0f, 0.f, 0.f}};  // 300 voxels
  EXPECT_THROW(nbv::kernels::markRays(origin, far, VoxelLattice(0.01), box, kNearest, sink, Isa::Scalar),
               std::invalid_argument);
}

}  // namespace
