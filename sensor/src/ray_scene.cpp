// The one place that talks to Embree: its handles live in RAII wrappers here, and its errors
// become SceneError exceptions. No Embree header reaches a public header.
#include "nbv/sensor/depth_camera.hpp"

#include "nbv/errors.hpp"

#include <embree3/rtcore.h>

#include <cmath>
#include <limits>
#include <string>

namespace nbv::sensor {

namespace {

const char* errorName(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
    default: return "unknown error";
  }
}

struct DeviceDeleter {
  void operator()(RTCDeviceTy* device) const { rtcReleaseDevice(device); }
};
struct SceneDeleter {
  void operator()(RTCSceneTy* scene) const { rtcReleaseScene(scene); }
};

}  // namespace

struct RayScene::Impl {
  std::unique_ptr<RTCDeviceTy, DeviceDeleter> device;
  std::unique_ptr<RTCSceneTy, SceneDeleter> scene;
  std::string last_error;  // written by Embree's callback during construction only

  unsigned object = RTC_INVALID_GEOMETRY_ID;
  unsigned ground = RTC_INVALID_GEOMETRY_ID;

  /// Attaches a triangle mesh to the scene; its geometry id.
  unsigned attach(const TriangleMesh& mesh) {
    RTCGeometry geometry = rtcNewGeometry(device.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
    check("new geometry");
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.vertices.size()));
    auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), mesh.triangles.size()));
    if (vertices == nullptr || indices == nullptr) {
      rtcReleaseGeometry(geometry);
      check("geometry buffers");
      throw SceneError("Embree: cannot allocate geometry buffers");
    }
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
      for (int k = 0; k < 3; ++k) vertices[3 * i + static_cast<std::size_t>(k)] = mesh.vertices[i][k];
    }
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
      for (int k = 0; k < 3; ++k) indices[3 * i + static_cast<std::size_t>(k)] = static_cast<unsigned>(mesh.triangles[i][k]);
    }
    rtcCommitGeometry(geometry);
    const unsigned id = rtcAttachGeometry(scene.get(), geometry);
    rtcReleaseGeometry(geometry);  // the scene holds it now
    return id;
  }

  /// Throws SceneError if Embree reported an error since the last check.
  void check(const char* what) {
    const RTCError code = rtcGetDeviceError(device.get());
    if (code != RTC_ERROR_NONE) {
      throw SceneError(std::string("Embree: ") + what + ": " + errorName(code) +
                       (last_error.empty() ? "" : " (" + last_error + ")"));
    }
  }
};

RayScene::RayScene(const TriangleMesh& mesh, const SceneOptions& options) : impl_(std::make_unique<Impl>()) {
  if (mesh.triangles.empty()) throw InvalidArgument("cannot build a ray scene without triangles");
  if (options.ground_plane && !(options.ground_half_extent_m > 0.0 && std::isfinite(options.ground_half_extent_m))) {
    throw InvalidArgument("ground plane half extent " + numberText(options.ground_half_extent_m) + " m must be positive");
  }
  for (const Eigen::Vector3i& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      if (t[k] < 0 || static_cast<std::size_t>(t[k]) >= mesh.vertices.size()) {
        throw InvalidArgument("triangle index " + std::to_string(t[k]) + " out of range");
      }
    }
  }
  impl_->device.reset(rtcNewDevice(nullptr));
  if (!impl_->device) throw SceneError(std::string("Embree: cannot create a device: ") + errorName(rtcGetDeviceError(nullptr)));
  rtcSetDeviceErrorFunction(
      impl_->device.get(),
      [](void* user, RTCError, const char* message) { static_cast<Impl*>(user)->last_error = message ? message : ""; },
      impl_.get());
  impl_->scene.reset(rtcNewScene(impl_->device.get()));
  impl_->check("new scene");

  impl_->object = impl_->attach(mesh);
  if (options.ground_plane) {  // two triangles at z = 0, facing up
    const auto e = static_cast<float>(options.ground_half_extent_m);
    TriangleMesh ground;
    ground.vertices = {{-e, -e, 0.0f}, {e, -e, 0.0f}, {e, e, 0.0f}, {-e, e, 0.0f}};
    ground.triangles = {{0, 1, 2}, {0, 2, 3}};
    impl_->ground = impl_->attach(ground);
  }
  rtcSetSceneFlags(impl_->scene.get(), RTC_SCENE_FLAG_ROBUST);
  rtcCommitScene(impl_->scene.get());
  impl_->check("commit scene");
}

RayScene::~RayScene() = default;
RayScene::RayScene(RayScene&&) noexcept = default;
RayScene& RayScene::operator=(RayScene&&) noexcept = default;

std::optional<RayHit> RayScene::intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction,
                                          float max_distance_m) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit query{};
  query.ray.org_x = origin.x();
  query.ray.org_y = origin.y();
  query.ray.org_z = origin.z();
  query.ray.dir_x = direction.x();
  query.ray.dir_y = direction.y();
  query.ray.dir_z = direction.z();
  query.ray.tnear = 0.0f;
  query.ray.tfar = max_distance_m;
  query.ray.mask = std::numeric_limits<unsigned>::max();
  query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene.get(), &context, &query);
  if (query.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  return RayHit{query.ray.tfar, query.hit.geomID == impl_->ground ? Surface::Ground : Surface::Object};
}

}  // namespace nbv::sensor
