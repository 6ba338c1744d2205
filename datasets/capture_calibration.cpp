#include "datasets/capture_calibration.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <thread>

#include "calib/camera_calibration.hpp"
#include "calib/camera_model.hpp"
#include "calib/half_sphere_calibration.hpp"
#include "calib/intrinsics.hpp"
#include "calib/laser_plane.hpp"
#include "calib/laser_plane_heights_record.hpp"
#include "calib/laser_plane_report.hpp"
#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/provenance.hpp"
#include "triangulation/half_sphere_profiles.hpp"
#include "triangulation/laser_plane_captures.hpp"
#include "triangulation/linear_sweep.hpp"
#include "triangulation/profile_io.hpp"
#include "triangulation/sweep.hpp"
#include "triangulation/triangulator.hpp"

namespace lasercell::datasets {
namespace {

std::string In(const std::string& dir, const std::string& relative) {
  return (std::filesystem::path(dir) / relative).string();
}

calib::CameraModel CalibrateCamera(const std::string& dir, const calib::BoardSpec& board,
                                   int threads, std::string* summary) {
  calib::IntrinsicsOptions options;
  options.model = calib::LensModelKind::kOpenCV8;
  options.threads =
      threads > 0 ? threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const std::string glob = In(dir, "images/chessboard_*.png");
  const calib::CalibrationImages images =
      calib::DetectCalibrationImages(io::GlobFiles(glob, "chessboard images"), board, {});
  calib::CheckEnoughViews(images, board, options.min_views, glob);
  const calib::IntrinsicsResult result = calib::CalibrateIntrinsicsFallingBackToOpencv5(
      images.views, board, images.width, images.height, options);
  if (const std::string reason = result.RejectionReason(); !reason.empty()) {
    throw InputError(glob + ": camera calibration rejected (" + reason + "): " + result.Summary());
  }
  *summary = (result.refitted_because.empty() ? std::string() : result.refitted_because + "; ") +
             result.Summary();
  return *result.camera;
}

LaserPlaneEntry CalibrateLaser(const std::string& dir, const calib::CameraModel& camera,
                               std::string* summary) {
  const calib::PlaneHeightsRecord record =
      calib::ReadPlaneHeightsYaml(In(dir, "records/planes.yaml"));
  const std::vector<std::string> files = triangulation::FindPlaneProfileFiles(In(dir, "profiles"));
  InputDigest digest;
  const auto captures =
      triangulation::LoadHeightCaptures(files, record.heights_mm, camera, &digest);
  calib::HeightPlaneOptions options;
  options.plate_normal_in_sensor = record.plate_normal_in_sensor;
  const calib::LaserPlaneResult result =
      calib::CalibrateLaserPlaneFromHeights(camera, captures, options);
  const std::string refusal = result.RefusalReason();
  if (!refusal.empty()) throw InputError(In(dir, "profiles") + ": laser plane refused: " + refusal);
  *summary = result.Summary();
  EdgeProvenance provenance;
  provenance.tool = std::string("lasercell calibrate laser ") + LASERCELL_VERSION;
  provenance.date = UtcTimestampIso();
  provenance.input_digest = digest.Text();
  return calib::LaserPlaneCellEntry(result, provenance);
}

StaticEdge CalibrateSpheres(const std::string& dir, const calib::CameraModel& camera,
                            const FrameGraph& cell, int threads, std::string* summary) {
  triangulation::SweepOptions options =
      triangulation::ReadLinearSweepRecord(In(dir, "records/linear_sweep.yaml")).Options();
  options.threads = threads;
  const std::string profiles = In(dir, "profiles/spheres.lcp");
  const std::string touches_file = In(dir, "records/touches.yaml");
  const std::string touches_text = io::ReadFileBytes(touches_file);
  const calib::SphereTouches touches = calib::ParseTouchesYaml(touches_text, touches_file);
  // Through the same camera and plane as every later sweep: the edge keeps its response to
  // their error modes so that a job counts the shared error once.
  const triangulation::HalfSphereFromProfiles out = triangulation::CalibrateHalfSpheresFromProfiles(
      cell, "cell.yaml", camera, triangulation::ReadProfiles(profiles), options, "laser", touches,
      {}, {"cell.yaml", profiles, touches_file, "sensor"});
  const calib::HalfSphereSweepResult& run = out.run;
  if (!run.calibrated) throw FileError(profiles, run.failure);
  *summary = run.calibration.Summary();
  InputDigest digest;
  digest.AddFile(profiles);
  digest.Add(touches_text);
  StaticEdge edge = calib::HalfSphereEdge(
      run.calibration, "sensor", calib::HalfSphereProvenance(run.calibration, digest.Text()));
  edge.sensor_response = triangulation::SensorResponseOf(run, cell, "laser");
  return edge;
}

}  // namespace

CaptureCalibration CalibrateCaptureFolder(const std::string& capture_dir,
                                          const std::string& out_dir, const calib::BoardSpec& board,
                                          const ProgressCallback& progress, int threads) {
  const auto start = std::chrono::steady_clock::now();
  CaptureCalibration out;
  std::filesystem::create_directories(out_dir);
  const calib::CameraModel camera =
      CalibrateCamera(capture_dir, board, threads, &out.camera_summary);
  out.camera_file = In(out_dir, "camera.cameramodel");
  calib::SaveCameraModel(out.camera_file, camera, "lasercell: " + out.camera_summary);
  if (progress) progress("camera", 1.0 / 3.0);
  // The camera as a job reads it back (the file, not the in-memory model).
  const calib::CameraModel saved = calib::LoadCameraModel(out.camera_file);
  const LaserPlaneEntry plane = CalibrateLaser(capture_dir, saved, &out.laser_summary);
  if (progress) progress("laser plane", 2.0 / 3.0);
  FrameGraph cell;
  cell.SetLaserPlane("laser", plane);
  cell.SetStaticEdge(CalibrateSpheres(capture_dir, saved, cell, threads, &out.spheres_summary));
  out.cell_file = In(out_dir, "cell.yaml");
  SaveFrameGraph(out.cell_file, cell);
  if (progress) progress("spheres", 1.0);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace lasercell::datasets
