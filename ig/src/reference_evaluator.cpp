#include "nbv/ig/reference_evaluator.hpp"

#include "nbv/errors.hpp"

#include <octomap/OcTree.h>

#include <string>
#include <unordered_map>

namespace nbv::ig {

namespace {
constexpr int kKeyOffset = 32768;  // OctoMap's tree_max_val at depth 16

octomap::OcTreeKey toKey(const Index3& ijk) {
  for (int a = 0; a < 3; ++a) {
    if (ijk[a] < -kKeyOffset || ijk[a] >= kKeyOffset) {
      throw InvalidArgument("the map extends beyond OctoMap's 16-bit key range");
    }
  }
  return {static_cast<octomap::key_type>(ijk.x() + kKeyOffset), static_cast<octomap::key_type>(ijk.y() + kKeyOffset),
          static_cast<octomap::key_type>(ijk.z() + kKeyOffset)};
}
/// Whether a face neighbour of `key` is free (measured, P_o below the free threshold): what
/// makes an unknown voxel a frontier voxel (fv).
bool hasFreeNeighbour(const octomap::OcTree& tree, const kernels::VoxelModel& model, const octomap::OcTreeKey& key) {
  for (int a = 0; a < 3; ++a) {
    for (const int s : {-1, 1}) {
      const int k = key[a] + s;
      if (k < 0 || k > 0xFFFF) continue;  // beyond OctoMap's keys: never measured
      octomap::OcTreeKey neighbour = key;
      neighbour[a] = static_cast<octomap::key_type>(k);
      const octomap::OcTreeNode* node = tree.search(neighbour);
      if (node != nullptr &&
          (kernels::voxelTerms(model, true, node->getLogOdds(), 0).flags & kernels::voxel_flag::kFree) != 0) {
        return true;
      }
    }
  }
  return false;
}

}  // namespace

struct ReferenceEvaluator::Octree {
  explicit Octree(double resolution) : tree(resolution) {}
  octomap::OcTree tree;
  std::unordered_map<octomap::OcTreeKey, std::int32_t, octomap::OcTreeKey::KeyHash> marks;
};

ReferenceEvaluator::ReferenceEvaluator(const OccupancyMap& map)
    : empty_like_(map.config()), octree_(std::make_unique<Octree>(map.config().resolution)) {
  octomap::OcTree& tree = octree_->tree;
  tree.setOccupancyThres(0.5);  // SEMANTICS.md "Views and rays": a ray ends at the first voxel with L >= 0
  for (const MeasuredVoxel& voxel : map.measuredVoxels()) {
    tree.setNodeValue(toKey(voxel.ijk), voxel.log_odds, /*lazy_eval=*/true);
  }
  tree.updateInnerOccupancy();
  tree.prune();
  for (const ProximityMark& mark : map.proximityMarks()) octree_->marks.emplace(toKey(mark.ijk), mark.distance);
}

ReferenceEvaluator::~ReferenceEvaluator() = default;

IgTable ReferenceEvaluator::evaluate(std::span<const Eigen::Isometry3d> T_world_cameras,
                                     std::span<const Eigen::Vector3d> directions_camera,
                                     const EvaluateOptions& options) const {
  options.validate();
  validateViews(empty_like_, T_world_cameras, directions_camera, options.walk.max_ray_depth);
  const kernels::VoxelModel model = options.snapshotOptions().voxelModel(empty_like_.config());
  const octomap::OcTree& tree = octree_->tree;

  IgTable table;
  table.metrics = options.table.metrics;
  table.sums.resize(T_world_cameras.size());
  const bool cast_rays = castsRays(options.table.metrics);
  octomap::KeyRay key_ray;
  for (std::size_t v = 0; v < T_world_cameras.size() && cast_rays; ++v) {
    for (const Eigen::Vector3d& direction : directions_camera) {
      const IgRay ray = igRay(T_world_cameras[v], direction, options.walk.max_ray_depth);
      const octomap::point3d origin(ray.origin.x(), ray.origin.y(), ray.origin.z());
      const octomap::point3d end(ray.end.x(), ray.end.y(), ray.end.z());
      octomap::OcTreeKey end_key;
      if (!tree.computeRayKeys(origin, end, key_ray) || !tree.coordToKeyChecked(end, end_key)) {
        throw InvalidArgument("a ray of view " + std::to_string(v) + " leaves OctoMap's key range");
      }
      key_ray.addKey(end_key);  // SEMANTICS.md "Views and rays": the voxel at max_ray_depth closes the ray
      kernels::RayAccumulator acc;
      for (const octomap::OcTreeKey& key : key_ray) {
        const octomap::OcTreeNode* node = tree.search(key);
        std::int32_t mark = 0;
        if (node == nullptr) {
          const auto it = octree_->marks.find(key);
          if (it != octree_->marks.end()) mark = it->second;
        }
        kernels::VoxelTerms terms = kernels::voxelTerms(model, node != nullptr, node != nullptr ? node->getLogOdds() : 0.0f, mark);
        if (model.frontier && (terms.flags & kernels::voxel_flag::kUnknown) != 0 && hasFreeNeighbour(tree, model, key)) {
          terms.flags |= kernels::voxel_flag::kFrontier;
        }
        acc.add(terms);
        if (node != nullptr && tree.isNodeOccupied(node)) break;  // the end voxel
      }
      table.sums[v].add(acc.finish(), acc.counts());
    }
  }
  fillValues(table, options.table.random_seed);
  return table;
}

}  // namespace nbv::ig
