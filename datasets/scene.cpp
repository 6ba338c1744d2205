#include "datasets/scene.hpp"

#include <embree3/rtcore.h>
#include <tbb/task_arena.h>

#include <array>
#include <cmath>
#include <string>

#include "core/error.hpp"

namespace lasercell::datasets {

namespace {

void EmbreeErrorHandler(void*, RTCError code, const char* message) {
  // Errors are collected with rtcGetDeviceError after each call; nothing to do here but keep
  // Embree from printing.
  (void)code;
  (void)message;
}

// One Embree device per process. Its thread count is left alone: Embree's TBB scheduler turns a
// "threads=N" into a process-wide tbb::global_control that stays for the device's lifetime, so
// "threads=1" made every later parallel loop of the process (localization in a benchmark that
// simulates first) single-threaded. The BVH builds are kept single-threaded, hence identical
// for any machine load, by committing inside a one-thread task arena (Scene::Commit); traversal
// is thread-safe regardless.
RTCDevice SharedDevice() {
  static RTCDevice device = [] {
    RTCDevice d = rtcNewDevice("set_affinity=0,verbose=0");
    if (d == nullptr) throw InternalError("Embree: rtcNewDevice failed");
    rtcSetDeviceErrorFunction(d, EmbreeErrorHandler, nullptr);
    return d;
  }();
  return device;
}

void CheckEmbree(RTCDevice device, const char* what) {
  const RTCError err = rtcGetDeviceError(device);
  if (err != RTC_ERROR_NONE) {
    throw InternalError(std::string("Embree error ") + std::to_string(static_cast<int>(err)) +
                        " in " + what);
  }
}

// Both roots of a t^2 + 2 b t + c = 0 (a > 0), numerically stable (Numerical Recipes 5.6).
std::optional<std::array<double, 2>> QuadraticRoots(double a, double b, double c) {
  if (!(a > 0)) return std::nullopt;
  const double disc = b * b - a * c;
  if (disc < 0) return std::nullopt;
  const double q = -(b + std::copysign(std::sqrt(disc), b));
  const double t1 = q / a;
  const double t2 = (q != 0) ? c / q : t1;
  return std::array<double, 2>{std::min(t1, t2), std::max(t1, t2)};
}

}  // namespace

double Material::AlbedoAt(const Eigen::Vector3d& p_in_scene) const {
  if (squares_x <= 0 || squares_y <= 0 || square_mm <= 0) return albedo;
  const Eigen::Vector3d q = pattern_from_scene * p_in_scene;
  const double fx = std::floor(q.x() / square_mm);
  const double fy = std::floor(q.y() / square_mm);
  if (fx < 0 || fy < 0 || fx >= squares_x || fy >= squares_y) return albedo;
  const auto i = static_cast<long>(fx);
  const auto j = static_cast<long>(fy);
  return ((i + j) % 2 == 0) ? dark_albedo : albedo;
}

struct Scene::Impl {
  RTCScene scene = nullptr;
  bool committed = false;
  ~Impl() {
    if (scene != nullptr) rtcReleaseScene(scene);
  }
};

Scene::Scene() : impl_(std::make_unique<Impl>()) {}
Scene::~Scene() = default;
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;

std::int32_t Scene::Add(SceneObject object) {
  LASERCELL_CHECK(!impl_->committed, "Scene::Add after Commit");
  object.geometry.CheckConsistent();
  const auto& pos = object.geometry.mesh.vertices.positions;
  std::vector<Eigen::Vector3d> normals;
  normals.reserve(object.geometry.mesh.faces.size());
  for (const Eigen::Vector3i& f : object.geometry.mesh.faces) {
    const Eigen::Vector3d n = (pos[f[1]] - pos[f[0]]).cross(pos[f[2]] - pos[f[0]]);
    normals.push_back(n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::UnitZ());
  }
  face_normals_.push_back(std::move(normals));
  objects_.push_back(std::move(object));
  return static_cast<std::int32_t>(objects_.size() - 1);
}

void Scene::Commit() {
  LASERCELL_CHECK(!impl_->committed, "Scene::Commit called twice");
  RTCDevice device = SharedDevice();
  impl_->scene = rtcNewScene(device);
  CheckEmbree(device, "rtcNewScene");
  rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
  for (std::size_t i = 0; i < objects_.size(); ++i) {
    const TriangleMesh& mesh = objects_[i].geometry.mesh;
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0,
                                                          RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                          mesh.vertices.positions.size()));
    auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), mesh.faces.size()));
    CheckEmbree(device, "rtcSetNewGeometryBuffer");
    for (std::size_t k = 0; k < mesh.vertices.positions.size(); ++k) {
      for (int c = 0; c < 3; ++c) v[3 * k + c] = static_cast<float>(mesh.vertices.positions[k][c]);
    }
    for (std::size_t k = 0; k < mesh.faces.size(); ++k) {
      for (int c = 0; c < 3; ++c) idx[3 * k + c] = static_cast<unsigned>(mesh.faces[k][c]);
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(impl_->scene, geom, static_cast<unsigned>(i));
    rtcReleaseGeometry(geom);
    CheckEmbree(device, "rtcAttachGeometry");
  }
  tbb::task_arena one_thread(1);
  one_thread.execute([&] { rtcCommitScene(impl_->scene); });
  CheckEmbree(device, "rtcCommitScene");
  impl_->committed = true;
}

std::optional<RayHit> Scene::IntersectFace(std::int32_t object, std::int32_t face,
                                           const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                           double t_hint, double slack_mm) const {
  const MeshPart& g = objects_[object].geometry;
  const AnalyticSurface& s = g.patches[g.face_patch[face]];
  const Eigen::Vector3d& n_face = face_normals_[object][face];
  RayHit hit;
  hit.object = object;
  hit.face = face;
  Eigen::Vector3d n = n_face;
  switch (s.kind) {
    case AnalyticSurface::Kind::kPlane:
    case AnalyticSurface::Kind::kNone: {
      // Analytic plane, or the triangle's own plane through its double-precision vertices.
      const Eigen::Vector3i& f = g.mesh.faces[face];
      const Eigen::Vector3d p0 =
          s.kind == AnalyticSurface::Kind::kPlane ? s.point : g.mesh.vertices.positions[f[0]];
      n = s.kind == AnalyticSurface::Kind::kPlane ? s.axis : n_face;
      const double denom = d.dot(n);
      if (denom == 0) return std::nullopt;
      hit.t_mm = (p0 - o).dot(n) / denom;
      hit.point = o + hit.t_mm * d;
      if (s.kind == AnalyticSurface::Kind::kNone) {
        // Barycentric containment with slack (the BVH already chose this triangle).
        const auto& P = g.mesh.vertices.positions;
        const Eigen::Vector3d a = P[f[0]], b = P[f[1]], c = P[f[2]];
        for (int e = 0; e < 3; ++e) {
          const Eigen::Vector3d& u = (e == 0) ? a : (e == 1) ? b : c;
          const Eigen::Vector3d& w = (e == 0) ? b : (e == 1) ? c : a;
          const double edge_len = (w - u).norm();
          const double signed_dist = (w - u).cross(hit.point - u).dot(n_face) / edge_len;
          if (signed_dist < -slack_mm) return std::nullopt;
        }
      }
      break;
    }
    case AnalyticSurface::Kind::kSphere:
    case AnalyticSurface::Kind::kCylinder: {
      // Quadric |r(t)|^2 = radius^2 with r the offset from the centre (sphere) or its part
      // perpendicular to the axis (cylinder).
      const bool sphere = s.kind == AnalyticSurface::Kind::kSphere;
      const Eigen::Vector3d oc = o - s.point;
      const Eigen::Vector3d op = sphere ? oc : Eigen::Vector3d(oc - oc.dot(s.axis) * s.axis);
      const Eigen::Vector3d dp = sphere ? d : Eigen::Vector3d(d - d.dot(s.axis) * s.axis);
      const auto roots =
          QuadraticRoots(dp.squaredNorm(), dp.dot(op), op.squaredNorm() - s.radius * s.radius);
      if (!roots) return std::nullopt;
      // Prefer the root where the surface faces the ray the way the hit triangle does (entry into
      // a ball, exit from a hole), then the one nearest the hint.
      const bool front = n_face.dot(d) < 0;
      double best_t = 0;
      int best_rank = 3;
      for (double t : *roots) {
        const Eigen::Vector3d radial = (op + t * dp) / s.radius;
        const Eigen::Vector3d oriented =
            radial.dot(n_face) >= 0 ? radial : Eigen::Vector3d(-radial);
        const int rank = ((oriented.dot(d) < 0) == front) ? 0 : 1;
        if (rank < best_rank ||
            (rank == best_rank && std::abs(t - t_hint) < std::abs(best_t - t_hint))) {
          best_rank = rank;
          best_t = t;
        }
      }
      hit.t_mm = best_t;
      hit.point = o + hit.t_mm * d;
      n = (op + best_t * dp).normalized();
      break;
    }
  }
  // Outward normal: the analytic normal turned to agree with the triangle's orientation (a hole
  // wall is a cylinder whose outward side faces its axis).
  hit.normal = n.dot(n_face) >= 0 ? n : Eigen::Vector3d(-n);
  return hit;
}

std::optional<RayHit> Scene::Intersect(const Eigen::Vector3d& origin,
                                       const Eigen::Vector3d& direction, double t_min,
                                       double t_max) const {
  LASERCELL_CHECK(impl_->committed, "Scene::Intersect before Commit");
  const Eigen::Vector3d d = direction.normalized();
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh;
  rh.ray.org_x = static_cast<float>(origin.x());
  rh.ray.org_y = static_cast<float>(origin.y());
  rh.ray.org_z = static_cast<float>(origin.z());
  rh.ray.dir_x = static_cast<float>(d.x());
  rh.ray.dir_y = static_cast<float>(d.y());
  rh.ray.dir_z = static_cast<float>(d.z());
  rh.ray.tnear = static_cast<float>(t_min);
  rh.ray.tfar =
      std::isfinite(t_max) ? static_cast<float>(t_max) : std::numeric_limits<float>::infinity();
  rh.ray.time = 0.0f;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  const auto object = static_cast<std::int32_t>(rh.hit.geomID);
  const auto face = static_cast<std::int32_t>(rh.hit.primID);
  // Double-precision refinement; generous slack because the float ray may pass an edge the
  // double ray does not (the point is then on the neighbour's plane to within float noise).
  // Curved patches may differ from their inscribed tessellation by more than float noise near
  // silhouettes (grazing rays), so they get a tolerance of the patch size.
  const MeshPart& g = objects_[object].geometry;
  const AnalyticSurface& surface = g.patches[g.face_patch[face]];
  const double tolerance = 1.0 + 1e-3 * rh.ray.tfar + 2.0 * surface.radius;
  auto hit = IntersectFace(object, face, origin, d, rh.ray.tfar, 1.0);
  if (!hit || !(hit->t_mm > t_min) || !(hit->t_mm < t_max) ||
      std::abs(hit->t_mm - rh.ray.tfar) > tolerance) {
    // Refinement failed (a silhouette of a tessellated surface): keep the triangle hit.
    RayHit fallback;
    fallback.object = object;
    fallback.face = face;
    fallback.t_mm = rh.ray.tfar;
    fallback.point = origin + fallback.t_mm * d;
    fallback.normal = face_normals_[object][face];
    return fallback;
  }
  return hit;
}

bool Scene::Occluded(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double t_min,
                     double t_max) const {
  LASERCELL_CHECK(impl_->committed, "Scene::Occluded before Commit");
  const Eigen::Vector3d d = direction.normalized();
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay ray;
  ray.org_x = static_cast<float>(origin.x());
  ray.org_y = static_cast<float>(origin.y());
  ray.org_z = static_cast<float>(origin.z());
  ray.dir_x = static_cast<float>(d.x());
  ray.dir_y = static_cast<float>(d.y());
  ray.dir_z = static_cast<float>(d.z());
  ray.tnear = static_cast<float>(t_min);
  ray.tfar =
      std::isfinite(t_max) ? static_cast<float>(t_max) : std::numeric_limits<float>::infinity();
  ray.time = 0.0f;
  ray.mask = 0xFFFFFFFFu;
  ray.id = 0;
  ray.flags = 0;
  rtcOccluded1(impl_->scene, &context, &ray);
  return ray.tfar < 0;  // Embree sets tfar = -inf on occlusion
}

std::int32_t Scene::Find(const std::string& name) const {
  for (std::size_t i = 0; i < objects_.size(); ++i) {
    if (objects_[i].name == name) return static_cast<std::int32_t>(i);
  }
  return -1;
}

TriangleMesh Scene::MergedMesh() const {
  MeshPart all;
  for (const SceneObject& o : objects_) all.Append(o.geometry);
  return all.mesh;
}

std::size_t Scene::TriangleCount() const {
  std::size_t n = 0;
  for (const SceneObject& o : objects_) n += o.geometry.mesh.faces.size();
  return n;
}

}  // namespace lasercell::datasets
