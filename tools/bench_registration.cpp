// The peers of `lasercell bench registration`: OpenCV cv::ppf_match_3d and PCL PPF + ICP on the
// same in-memory clouds as lasercell. The only file of the tool that includes OpenCV or PCL
// headers (PCL compiles slowly); see bench_registration.hpp.
#include "tools/bench_registration.hpp"

#include <pcl/console/print.h>
#include <pcl/features/ppf.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/icp.h>
#include <pcl/registration/ppf_registration.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/surface_matching.hpp>
#include <opencv2/surface_matching/ppf_helpers.hpp>
#include <pcl/features/impl/ppf.hpp>
#include <pcl/registration/impl/ppf_registration.hpp>
#include <random>
#include <sstream>

#include "core/random.hpp"
#include "registration/icp.hpp"
#include "registration/localize_in_cloud.hpp"
#include "registration/verification.hpp"

namespace lasercell::tools {
namespace {

using Clock = std::chrono::steady_clock;
using PclCloud = pcl::PointCloud<pcl::PointNormal>;

// PCL's point-to-plane ICP with its iteration count exposed, and convergence tolerances set like
// lasercell's IcpOptions (update below 1e-3 mm and 1e-5 rad; PCL compares the squared
// translation and the rotation's cosine, the latter in float).
class PclIcp : public pcl::IterativeClosestPointWithNormals<pcl::PointNormal, pcl::PointNormal> {
 public:
  PclIcp(double max_distance_mm, int max_iterations) {
    setMaxCorrespondenceDistance(max_distance_mm);
    setMaximumIterations(max_iterations);
    setTransformationEpsilon(1e-3 * 1e-3);
    setTransformationRotationEpsilon(std::cos(1e-5));
  }
  int Iterations() const { return nr_iterations_; }
};

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

std::string Format(const char* format, double a, double b = 0.0, double c = 0.0) {
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, format, a, b, c);
  return buffer;
}

// Eigen -> cv::Mat N x 6 float (x y z nx ny nz), unit normals, as ppf_helpers' loadPLYSimple.
cv::Mat ToCvMat(const PointCloud& cloud) {
  cv::Mat mat(static_cast<int>(cloud.size()), 6, CV_32F);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    float* row = mat.ptr<float>(static_cast<int>(i));
    const Eigen::Vector3d n = cloud.normals[i].normalized();
    for (int k = 0; k < 3; ++k) {
      row[k] = static_cast<float>(cloud.positions[i](k));
      row[3 + k] = static_cast<float>(n(k));
    }
  }
  return mat;
}

Eigen::Isometry3d FromCv(const cv::Matx44d& m) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) pose.matrix()(r, c) = m(r, c);
  }
  return pose;
}

Eigen::Isometry3d FromPcl(const Eigen::Matrix4f& m) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.matrix().topRows<3>() = m.cast<double>().topRows<3>();
  return pose;
}

Eigen::Matrix4f ToPcl(const Eigen::Isometry3d& pose) { return pose.matrix().cast<float>(); }

PclCloud::Ptr ToPcl(const std::vector<Eigen::Vector3d>& points,
                    const std::vector<Eigen::Vector3d>& normals) {
  auto cloud = std::make_shared<PclCloud>();
  cloud->resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    pcl::PointNormal& p = (*cloud)[i];
    const Eigen::Vector3f n = normals[i].normalized().cast<float>();
    p.x = static_cast<float>(points[i].x());
    p.y = static_cast<float>(points[i].y());
    p.z = static_cast<float>(points[i].z());
    p.normal_x = n.x();
    p.normal_y = n.y();
    p.normal_z = n.z();
    p.curvature = 0.0f;
  }
  return cloud;
}

// pcl::VoxelGrid averages every field (positions and normals); normals are re-normalized.
PclCloud::Ptr VoxelSubsample(const PclCloud::Ptr& cloud, double leaf_mm) {
  pcl::VoxelGrid<pcl::PointNormal> grid;
  const auto leaf = static_cast<float>(leaf_mm);
  grid.setLeafSize(leaf, leaf, leaf);
  grid.setInputCloud(cloud);
  auto out = std::make_shared<PclCloud>();
  grid.filter(*out);
  for (auto& p : *out) p.getNormalVector3fMap().normalize();
  return out;
}

// PCL's point-to-plane ICP on a fixed target (the ICP-only comparison).
struct PclIcpTrial {
  Eigen::Isometry3d target_from_source = Eigen::Isometry3d::Identity();
  double ms = 0.0;
  int iterations = 0;
};

class PclPointToPlaneIcp {
 public:
  PclPointToPlaneIcp(const std::vector<Eigen::Vector3d>& target,
                     const std::vector<Eigen::Vector3d>& target_normals, double max_distance_mm,
                     int max_iterations)
      : icp_(max_distance_mm, max_iterations) {
    icp_.setInputTarget(ToPcl(target, target_normals));
  }
  PclIcpTrial Align(const std::vector<Eigen::Vector3d>& source,
                    const std::vector<Eigen::Vector3d>& source_normals,
                    const Eigen::Isometry3d& initial) {
    PclIcpTrial trial;
    const PclCloud::Ptr cloud = ToPcl(source, source_normals);
    PclCloud aligned;
    const auto start = Clock::now();
    icp_.setInputSource(cloud);
    icp_.align(aligned, ToPcl(initial));
    trial.ms = MsSince(start);
    trial.iterations = icp_.Iterations();
    trial.target_from_source = FromPcl(icp_.getFinalTransformation());
    return trial;
  }

 private:
  PclIcp icp_;
};

}  // namespace

double CpuMs() { return 1000.0 * static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

std::string Ms(double ms) {
  if (!(ms >= 0.0)) return "-";
  char b[32];
  std::snprintf(b, sizeof b, ms < 100.0 ? "%.1f" : "%.0f", ms);
  return b;
}

// Model build (median of up to 5), then LocalizeInCloud `runs` times (median).
std::vector<BenchRow> RunLasercell(const PointCloud& model_cloud, const PointCloud& scene,
                                   const LasercellBenchOptions& options,
                                   registration::PpfModel* model) {
  registration::PpfModelOptions model_options;
  model_options.threads = options.threads;
  std::vector<double> build_ms;
  for (int i = 0; i < std::min(options.runs, 5); ++i) {
    const auto start = Clock::now();
    *model = registration::PpfModel::Build(model_cloud, model_options);
    build_ms.push_back(MsSince(start));
  }
  registration::LocalizeOptions localize;
  localize.threads = options.threads;
  std::vector<double> total_ms, icp_ms, cpu_ms;
  registration::LocalizationResult result;
  for (int i = 0; i < options.runs; ++i) {
    const auto start = Clock::now();
    const double cpu_start = CpuMs();
    result = registration::LocalizeInCloud(scene, *model, localize);
    total_ms.push_back(MsSince(start));
    cpu_ms.push_back(CpuMs() - cpu_start);
    icp_ms.push_back(result.timings.icp_ms);
  }
  const double total = Median(total_ms), icp = Median(icp_ms);
  BenchRow coarse{
      "lasercell (coarse, before ICP)", "", Median(build_ms), total - icp, -1.0, -1.0, -1.0, {}};
  BenchRow refined{"lasercell", "", coarse.build_ms, total - icp, icp, total, Median(cpu_ms), {}};
  std::ostringstream note;
  const auto& t = result.timings;
  note << "defaults; median of " << options.runs << " runs; " << model->points().size()
       << " model points, " << result.sampled_points
       << " scene points after voxel grid; last run: subsample " << Ms(t.subsample_ms)
       << ", kd-tree " << Ms(t.kdtree_ms) << ", voting " << Ms(t.matching_ms) << ", clustering "
       << Ms(t.clustering_ms) << ", verification " << Ms(t.verification_ms) << " ms";
  refined.note = note.str();
  coarse.note = "cluster pose of the same candidates";
  for (const auto& c : result.candidates) {
    coarse.poses.push_back(c.coarse_scene_from_model);
    refined.poses.push_back(c.scene_from_model);
  }
  return {coarse, refined};
}

std::vector<BenchRow> RunOpenCvPpf(const PointCloud& model, const PointCloud& scene,
                                   const OpenCvBenchOptions& options) {
  cv::setNumThreads(options.threads == 0 ? -1 : options.threads);
  const cv::Mat model_mat = ToCvMat(model), scene_mat = ToCvMat(scene);
  // Trained min(runs, 5) times like lasercell's model (median); the last detector is used.
  std::unique_ptr<cv::ppf_match_3d::PPF3DDetector> detector;
  std::vector<double> train_ms;
  for (int i = 0; i < std::min(options.runs, 5); ++i) {
    detector = std::make_unique<cv::ppf_match_3d::PPF3DDetector>(options.relative_sampling_step,
                                                                 options.relative_distance_step);
    const auto start = Clock::now();
    detector->trainModel(model_mat);
    train_ms.push_back(MsSince(start));
  }

  std::vector<BenchRow> rows;
  for (double step : options.scene_sample_steps) {
    const std::string label = options.label + " 1/" + Format("%.0f", 1.0 / step);
    BenchRow coarse{label, "", Median(train_ms), -1.0, -1.0, -1.0, -1.0, {}};
    coarse.note =
        Format("PPF3DDetector(%.3g, %.3g), ", options.relative_sampling_step,
               options.relative_distance_step) +
        Format("match(scene, 1/%.0f, %.3g); ", 1.0 / step, options.relative_scene_distance) +
        Format("medians of %.0f runs (training: of %.0f)", options.runs,
               static_cast<double>(train_ms.size()));
    BenchRow refined = coarse;
    refined.method = label + " + ICP";
    refined.note = "+ cv::ppf_match_3d::ICP(100, 0.005, 2.5, 8) on the top " +
                   std::to_string(options.icp_poses) + " poses (model: all points)";
    std::vector<double> match_ms, match_cpu, icp_ms, icp_cpu;
    for (int run = 0; run < options.runs; ++run) {
      std::vector<cv::ppf_match_3d::Pose3DPtr> results;
      auto start = Clock::now();
      double cpu_start = CpuMs();
      detector->match(scene_mat, results, step, options.relative_scene_distance);
      match_ms.push_back(MsSince(start));
      match_cpu.push_back(CpuMs() - cpu_start);
      coarse.poses.clear();
      for (const auto& r : results) coarse.poses.push_back(FromCv(r->pose));
      // registerModelToScene refines the poses in place: each run gets its own copies.
      std::vector<cv::ppf_match_3d::Pose3DPtr> top;
      for (std::size_t k = 0; k < std::min(options.icp_poses, results.size()); ++k)
        top.push_back(results[k]->clone());
      refined.poses.clear();
      if (top.empty()) continue;
      cv::ppf_match_3d::ICP icp(100, 0.005f, 2.5f, 8);
      start = Clock::now();
      cpu_start = CpuMs();
      icp.registerModelToScene(model_mat, scene_mat, top);
      icp_ms.push_back(MsSince(start));
      icp_cpu.push_back(CpuMs() - cpu_start);
      for (const auto& r : top) refined.poses.push_back(FromCv(r->pose));
    }
    coarse.match_ms = coarse.total_ms = Median(match_ms);
    coarse.total_cpu_ms = Median(match_cpu);
    refined.match_ms = coarse.match_ms;
    refined.icp_ms = icp_ms.empty() ? -1.0 : Median(icp_ms);
    refined.total_ms = refined.match_ms + std::max(0.0, refined.icp_ms);
    refined.total_cpu_ms = coarse.total_cpu_ms + (icp_cpu.empty() ? 0.0 : Median(icp_cpu));
    rows.push_back(std::move(coarse));
    rows.push_back(std::move(refined));
  }
  return rows;
}

std::vector<BenchRow> RunPclPpf(const PointCloud& model, const PointCloud& scene,
                                const PclBenchOptions& options) {
  pcl::console::setVerbosityLevel(
      pcl::console::L_WARN);  // PPFRegistration prints progress at L_INFO
  const PclCloud::Ptr model_full = ToPcl(model.positions, model.normals);
  const PclCloud::Ptr scene_full = ToPcl(scene.positions, scene.normals);

  // Offline, min(runs, 5) times like lasercell's model (median): voxel grid, every ordered pair's
  // feature (PPFEstimation), the hash map.
  PclCloud::Ptr model_sampled;
  std::shared_ptr<pcl::PointCloud<pcl::PPFSignature>> features;
  std::shared_ptr<pcl::PPFHashMapSearch> search;
  std::vector<double> build_ms;
  for (int i = 0; i < std::min(options.runs, 5); ++i) {
    const auto start = Clock::now();
    model_sampled = VoxelSubsample(model_full, options.sampling_step_mm);
    pcl::PPFEstimation<pcl::PointNormal, pcl::PointNormal, pcl::PPFSignature> estimation;
    estimation.setInputCloud(model_sampled);
    estimation.setInputNormals(model_sampled);
    features = std::make_shared<pcl::PointCloud<pcl::PPFSignature>>();
    estimation.compute(*features);
    search = std::make_shared<pcl::PPFHashMapSearch>(static_cast<float>(options.angle_step_rad),
                                                     static_cast<float>(options.distance_step_mm));
    search->setInputFeatureCloud(features);
    build_ms.push_back(MsSince(start));
  }

  // How many model pairs a key returns (pcl#5288 reported one; PCL 1.13 stores a multimap).
  std::size_t looked_up = 0, returned = 0;
  std::vector<std::pair<std::size_t, std::size_t>> found;
  for (std::size_t i = 0; i < features->size() && looked_up < 2000; i += 97) {
    pcl::PPFSignature f = (*features)[i];
    if (!std::isfinite(f.f1)) continue;
    search->nearestNeighborSearch(f.f1, f.f2, f.f3, f.f4, found);
    ++looked_up;
    returned += found.size();
  }

  // Online, `runs` times: scene voxel grid, PPFRegistration (votes, clustering), then
  // point-to-plane ICP from its pose.
  BenchRow coarse{"PCL PPFRegistration", "", Median(build_ms), -1.0, -1.0, -1.0, -1.0, {}};
  BenchRow refined = coarse;
  refined.method = "PCL PPFRegistration + ICP";
  std::vector<double> match_ms, match_cpu, icp_ms, icp_cpu;
  std::size_t scene_points = 0;
  int iterations = 0;
  for (int run = 0; run < options.runs; ++run) {
    auto start = Clock::now();
    double cpu_start = CpuMs();
    const PclCloud::Ptr scene_sampled = VoxelSubsample(scene_full, options.sampling_step_mm);
    pcl::PPFRegistration<pcl::PointNormal, pcl::PointNormal> registration;
    registration.setSceneReferencePointSamplingRate(options.reference_stride);
    registration.setPositionClusteringThreshold(static_cast<float>(options.cluster_translation_mm));
    registration.setRotationClusteringThreshold(static_cast<float>(options.cluster_rotation_rad));
    registration.setSearchMethod(search);
    registration.setInputSource(model_sampled);
    registration.setInputTarget(scene_sampled);
    PclCloud aligned;
    registration.align(aligned);
    match_ms.push_back(MsSince(start));
    match_cpu.push_back(CpuMs() - cpu_start);
    scene_points = scene_sampled->size();
    coarse.poses.clear();
    refined.poses.clear();
    if (!registration.hasConverged()) continue;
    coarse.poses.push_back(FromPcl(registration.getFinalTransformation()));
    start = Clock::now();
    cpu_start = CpuMs();
    PclIcp icp(options.icp_max_distance_mm, options.icp_iterations);
    icp.setInputSource(model_full);
    icp.setInputTarget(scene_full);
    icp.align(aligned, ToPcl(coarse.poses.front()));
    icp_ms.push_back(MsSince(start));
    icp_cpu.push_back(CpuMs() - cpu_start);
    refined.poses.push_back(FromPcl(icp.getFinalTransformation()));
    iterations = icp.Iterations();
  }
  coarse.match_ms = coarse.total_ms = refined.match_ms = Median(match_ms);
  coarse.total_cpu_ms = Median(match_cpu);
  refined.icp_ms = icp_ms.empty() ? -1.0 : Median(icp_ms);
  refined.total_ms = refined.match_ms + std::max(0.0, refined.icp_ms);
  refined.total_cpu_ms = coarse.total_cpu_ms + (icp_cpu.empty() ? 0.0 : Median(icp_cpu));

  std::ostringstream note;
  note << "voxel " << Format("%.1f", options.sampling_step_mm) << " mm: " << model_sampled->size()
       << " model / " << scene_points << " scene points, stride " << options.reference_stride
       << "; "
       << Format("%.2f",
                 looked_up ? static_cast<double>(returned) / static_cast<double>(looked_up) : 0.0)
       << " model pairs per looked-up key; medians of " << options.runs << " runs (build: of "
       << build_ms.size() << ")";
  coarse.note = note.str();
  refined.note =
      "+ IterativeClosestPointWithNormals (point-to-plane), model (all points) -> "
      "scene (all points), " +
      Format("max distance %.1f mm, <= %.0f iterations, %.0f iterations run (last run)",
             options.icp_max_distance_mm, options.icp_iterations, iterations);
  return {coarse, refined};
}

nlohmann::json RunIcpComparison(const registration::PpfModel& model, const PointCloud& scene,
                                const Eigen::Isometry3d& reference, const PoseEvaluator& evaluate,
                                const IcpComparisonOptions& options) {
  const double diameter = model.diameter_mm();
  registration::IcpOptions icp;
  icp.max_correspondence_distance_mm = 0.03 * diameter;
  icp.threads = options.threads;
  registration::VerificationOptions select;
  select.support_distance_mm = 0.02 * diameter;
  select.overlap_band_mm = icp.max_correspondence_distance_mm;
  std::unique_ptr<PclPointToPlaneIcp> pcl;
  if (options.with_pcl) {
    pcl = std::make_unique<PclPointToPlaneIcp>(
        model.refinement_points(), model.refinement_normals(), icp.max_correspondence_distance_mm,
        icp.max_iterations);
  }
  std::vector<Eigen::Vector3d> scene_normals = scene.normals;
  for (auto& n : scene_normals) n.normalize();

  std::mt19937_64 rng(4);
  std::normal_distribution<double> g(0.0, 1.0);
  const Eigen::Vector3d centre = reference * model.model_from_centered().translation();
  std::vector<double> start_rms, ours_ms, ours_rms, ours_it, pcl_ms, pcl_rms, pcl_it;
  for (int k = 0; k < options.starts; ++k) {
    const Eigen::Vector3d axis = Draws<3>(g, rng).normalized();
    const Eigen::Vector3d shift = 5.0 * Draws<3>(g, rng).normalized();
    const Eigen::Isometry3d delta = Eigen::Translation3d(centre + shift) *
                                    Eigen::AngleAxisd(3.0 * std::numbers::pi / 180.0, axis) *
                                    Eigen::Translation3d(-centre);
    const Eigen::Isometry3d start = delta * reference;
    start_rms.push_back(evaluate(start).rms_mm);
    std::vector<std::uint32_t> overlap;
    registration::VerifyPose(scene.positions, model, start, registration::Viewpoint{}, select,
                             &overlap);
    const std::size_t n = overlap.size(), m = std::min<std::size_t>(n, 1500);
    std::vector<Eigen::Vector3d> source, source_normals;
    for (std::size_t i = 0; i < m; ++i) {
      source.push_back(scene.positions[overlap[i * n / m]]);
      source_normals.push_back(scene_normals[overlap[i * n / m]]);
    }
    const Eigen::Isometry3d centered_from_scene = (start * model.model_from_centered()).inverse();
    auto t = Clock::now();
    const registration::IcpResult ours = registration::AlignIcp(
        source, model.refinement_tree(), model.refinement_normals(), centered_from_scene, icp);
    ours_ms.push_back(MsSince(t));
    ours_it.push_back(ours.iterations);
    ours_rms.push_back(
        evaluate(ours.target_from_source.inverse() * model.model_from_centered().inverse()).rms_mm);
    if (pcl) {
      // The first call builds PCL's target kd-tree; it is repeated so that no trial times it.
      if (k == 0) pcl->Align(source, source_normals, centered_from_scene);
      const PclIcpTrial trial = pcl->Align(source, source_normals, centered_from_scene);
      pcl_ms.push_back(trial.ms);
      pcl_it.push_back(trial.iterations);
      pcl_rms.push_back(
          evaluate(trial.target_from_source.inverse() * model.model_from_centered().inverse())
              .rms_mm);
    }
  }
  std::printf(
      "\nICP alone: %d seeded starts 3 deg / 5 mm about the model centre from the reference "
      "(start offset median %.1f mm RMS, max %.1f); source = scene points selected around the "
      "start (<= 1500), target = %zu model points; max distance %.1f mm, <= %d iterations; "
      "threads %d\n\n",
      options.starts, Median(start_rms), *std::max_element(start_rms.begin(), start_rms.end()),
      model.refinement_points().size(), icp.max_correspondence_distance_mm, icp.max_iterations,
      options.threads);
  std::printf(
      "| ICP | median ms | median iterations | median RMS error mm | max RMS error mm | "
      "within 0.1 mm | within 2 mm |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  nlohmann::json out = nlohmann::json::array();
  auto row = [&](const char* name, const std::vector<double>& ms, const std::vector<double>& it,
                 const std::vector<double>& rms) {
    const auto count = [&](double limit) {
      return std::count_if(rms.begin(), rms.end(), [&](double r) { return r <= limit; });
    };
    std::printf("| %s | %s | %.0f | %.3f | %.3f | %ld/%zu | %ld/%zu |\n", name,
                Ms(Median(ms)).c_str(), Median(it), Median(rms),
                *std::max_element(rms.begin(), rms.end()), static_cast<long>(count(0.1)),
                rms.size(), static_cast<long>(count(2.0)), rms.size());
    out.push_back({{"method", name},
                   {"median_ms", Median(ms)},
                   {"rms_error_mm", rms},
                   {"ms", ms},
                   {"iterations", it}});
  };
  row("lasercell AlignIcp (point-to-plane, Tukey)", ours_ms, ours_it, ours_rms);
  if (pcl)
    row("PCL IterativeClosestPointWithNormals (point-to-plane LLS)", pcl_ms, pcl_it, pcl_rms);
  // Time per iteration: the median over the starts of each run's ms / iterations.
  auto per_iteration = [](const std::vector<double>& ms, const std::vector<double>& it) {
    std::vector<double> v;
    for (std::size_t k = 0; k < ms.size(); ++k) v.push_back(ms[k] / std::max(1.0, it[k]));
    return Median(v);
  };
  const double ours_per = per_iteration(ours_ms, ours_it);
  out[0]["median_ms_per_iteration"] = ours_per;
  std::printf("\nPer iteration (median over the starts of ms / iterations): lasercell %.2f ms",
              ours_per);
  if (pcl) {
    const double pcl_per = per_iteration(pcl_ms, pcl_it);
    out[1]["median_ms_per_iteration"] = pcl_per;
    std::printf(", PCL %.2f ms (%.1fx); whole runs %.1fx", pcl_per, pcl_per / ours_per,
                Median(pcl_ms) / Median(ours_ms));
  }
  std::printf("\n");
  return out;
}

}  // namespace lasercell::tools
