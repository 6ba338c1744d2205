#pragma once
// The methods of `lasercell bench registration` (bench_registration.cpp): lasercell's
// LocalizeInCloud and its peer libraries, OpenCV cv::ppf_match_3d (PPF3DDetector + its ICP) and
// PCL (PPFEstimation + PPFHashMapSearch + PPFRegistration, IterativeClosestPointWithNormals), run
// on lasercell's in-memory clouds. The
// conversions Eigen <-> cv::Mat / pcl::PointCloud<pcl::PointNormal> live only in that file, so
// no other file of the tool compiles OpenCV or PCL headers. Also here: the pose evaluation against
// the reference and the ICP-only comparison (lasercell AlignIcp vs PCL point-to-plane ICP).
// Poses are scene_from_model (model frame as in the model file). Units: mm, rad; times in ms.

#include <Eigen/Geometry>
#include <cmath>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <vector>

#include "core/point_cloud.hpp"
#include "core/se3.hpp"
#include "core/stats.hpp"
#include "registration/kdtree.hpp"
#include "registration/ppf_model.hpp"

namespace lasercell::tools {

/// One method (or one stage of a method) of the benchmark, as the table shows it.
struct BenchRow {
  std::string method;                    ///< e.g. "OpenCV PPF 1/10 + ICP".
  std::string note;                      ///< Parameters, caveats.
  double build_ms = -1.0;                ///< Model build / training; < 0: not applicable.
  double match_ms = -1.0;                ///< Detection before ICP; < 0: not applicable.
  double icp_ms = -1.0;                  ///< ICP; < 0: not run.
  double total_ms = -1.0;                ///< End to end, model prebuilt, files parsed.
  double total_cpu_ms = -1.0;            ///< Process CPU time of total_ms (fair under load).
  std::vector<Eigen::Isometry3d> poses;  ///< Ranked scene_from_model, best first; may be empty.
};

/// lasercell's LocalizeInCloud at default options.
struct LasercellBenchOptions {
  int runs =
      20;  ///< LocalizeInCloud runs (median reported); the model is built min(runs, 5) times.
  int threads = 1;  ///< Threads of the model build and of LocalizeInCloud.
};

/// Two rows: the candidates' cluster poses (coarse, before ICP), then the refined poses with the
/// median times. The built model is left in *model.
std::vector<BenchRow> RunLasercell(const PointCloud& model_cloud, const PointCloud& scene,
                                   const LasercellBenchOptions& options,
                                   registration::PpfModel* model);

/// OpenCV cv::ppf_match_3d as its sample uses it: PPF3DDetector(sampling, 0.05) trained ONCE on the
/// model, match at each relativeSceneSampleStep, its ICP(100, 0.005, 2.5, 8) on the top poses.
struct OpenCvBenchOptions {
  double relative_sampling_step = 0.025;  ///< Model sampling relative to the diameter.
  double relative_distance_step = 0.05;   ///< Feature distance step relative to the diameter.
  double relative_scene_distance = 0.05;  ///< Scene sampling relative to the diameter.
  std::vector<double> scene_sample_steps = {0.1, 0.025};  ///< relativeSceneSampleStep values.
  std::size_t icp_poses = 2;  ///< Top poses refined by ICP (the sample: 2).
  int threads = 1;            ///< cv::setNumThreads; 0 = OpenCV's default.
  int runs = 20;  ///< Match and ICP runs (medians); trained min(runs, 5) times (median).
  std::string label = "OpenCV PPF";  ///< Row label, followed by " 1/<scene step>".
};

/// Two rows per scene sample step: the detector's ranked poses (last run), then the same after
/// ICP; times are medians over `runs`. The training time is in build_ms of every row.
std::vector<BenchRow> RunOpenCvPpf(const PointCloud& model, const PointCloud& scene,
                                   const OpenCvBenchOptions& options);

/// PCL PPF with the same quantization as a lasercell model, on voxel-subsampled clouds.
struct PclBenchOptions {
  double sampling_step_mm = 10.0;        ///< VoxelGrid leaf for model and scene.
  double distance_step_mm = 10.0;        ///< PPFHashMapSearch distance step.
  double angle_step_rad = 0.2094;        ///< PPFHashMapSearch angle step.
  unsigned reference_stride = 5;         ///< setSceneReferencePointSamplingRate.
  double cluster_translation_mm = 30.0;  ///< setPositionClusteringThreshold.
  double cluster_rotation_rad = 0.419;   ///< setRotationClusteringThreshold.
  double icp_max_distance_mm = 10.0;     ///< ICP max correspondence distance.
  int icp_iterations = 30;               ///< ICP max iterations.
  int runs = 20;  ///< Match and ICP runs (medians); the model is built min(runs, 5) times.
};

/// Two rows: PPFRegistration's pose, then pcl::IterativeClosestPointWithNormals (point-to-plane;
/// source: the whole model, target: the whole scene) from it; medians over `runs`. `note` of the
/// first row says how many model pairs the hash map returns per looked-up key.
std::vector<BenchRow> RunPclPpf(const PointCloud& model, const PointCloud& scene,
                                const PclBenchOptions& options);

/// One PCL point-to-plane ICP run for the ICP-only comparison.
/// Process CPU time, ms (std::clock): with one thread, the time the work needed on an idle core.
double CpuMs();
/// Milliseconds for the tables: "-" when negative or NaN, 1 decimal below 100 ms. (Medians are
/// core/stats.hpp's Median: the element n/2.)
std::string Ms(double ms);

/// Pose error of a scene_from_model against the reference, in the table's terms.
struct PoseError {
  double rotation_deg = 0.0;  ///< Rotation angle between the poses.
  double centroid_mm = 0.0;   ///< Displacement of the model centroid.
  double rms_mm = 0.0;        ///< RMS displacement of all model points.
  double within_2mm = 0.0;    ///< Fraction of model points within 2 mm of a scene point.
};

/// Evaluates poses against the reference (model points, scene kd-tree for the 2 mm fraction).
class PoseEvaluator {
 public:
  PoseEvaluator(const PointCloud& model, const PointCloud& scene,
                const Eigen::Isometry3d& reference)
      : model_(model.positions),
        centroid_(model.Centroid()),
        reference_(reference),
        scene_tree_(scene.positions) {}
  PoseError operator()(const Eigen::Isometry3d& pose) const {
    PoseError e;
    e.rotation_deg = RotationDistance(pose, reference_) * 180.0 / std::numbers::pi;
    e.centroid_mm = (pose * centroid_ - reference_ * centroid_).norm();
    double sum = 0.0;
    std::size_t close = 0;
    for (const auto& p : model_) {
      sum += (pose * p - reference_ * p).squaredNorm();
      registration::Neighbor nn;
      scene_tree_.Nearest(pose * p, &nn);
      close += nn.distance_sq <= 4.0 ? 1 : 0;
    }
    e.rms_mm = std::sqrt(sum / static_cast<double>(model_.size()));
    e.within_2mm = static_cast<double>(close) / static_cast<double>(model_.size());
    return e;
  }

 private:
  std::vector<Eigen::Vector3d> model_;
  Eigen::Vector3d centroid_;
  Eigen::Isometry3d reference_;
  registration::KdTree scene_tree_;
};

/// Options of RunIcpComparison.
struct IcpComparisonOptions {
  int starts = 20;       ///< Seeded perturbations of the reference (3 deg, 5 mm about the centre).
  int threads = 1;       ///< lasercell ICP threads.
  bool with_pcl = true;  ///< Also run PCL's point-to-plane ICP.
};

/// ICP alone from seeded perturbations of the reference: lasercell's AlignIcp and PCL's
/// IterativeClosestPointWithNormals (point-to-plane LLS, no robust kernel) get the same source
/// (scene points the projection grid selects around the start, thinned to 1500 as LocalizeInCloud
/// does), the same target (the model's refinement points), the same start, max distance,
/// iteration limit and tolerances. PCL's target kd-tree is built untimed (ours is prebuilt in the
/// model). Prints a Markdown table; returns its rows as JSON.
nlohmann::json RunIcpComparison(const registration::PpfModel& model, const PointCloud& scene,
                                const Eigen::Isometry3d& reference, const PoseEvaluator& evaluate,
                                const IcpComparisonOptions& options);

}  // namespace lasercell::tools
