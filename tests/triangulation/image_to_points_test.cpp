// Items 4 + 5 together: a raw laser-line image of the simulator's white plane -> peaks ->
// triangulated points on the true plane, within the scatter the peak noise predicts.
// Simulation profile: ideal (SimConfig{}, and ImageRenderOptions{} for the raw image).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "calib/camera_model.hpp"
#include "datasets/camera_images.hpp"
#include "datasets/cell.hpp"
#include "datasets/laser_renderer.hpp"
#include "datasets/simulate.hpp"
#include "triangulation/peak_detection.hpp"
#include "triangulation/triangulator.hpp"

namespace lasercell::triangulation {
namespace {

TEST(ImageToPoints, RawImageOfThePlaneTriangulatesOntoThePlane) {
  datasets::SimConfig config;
  const datasets::CellTruth truth = datasets::MakeCellTruth(config);
  const double height = 200.0;
  const datasets::Scene scene = datasets::MakePlaneScene(truth.layout, height, {2000, 2000});
  const datasets::LaserRenderer renderer(scene, truth.sensor, config.render);
  const datasets::LinearSweep sweep = datasets::MakeLinearSweep(config, truth.sensor);
  const Eigen::Isometry3d cell_from_sensor = sweep.At(1.0);
  datasets::ExposureTruth ex = renderer.RenderExact(cell_from_sensor);
  // Keep the stripe below saturation (amplitude 120 gray levels) so the estimator is tested,
  // not the plateau rule.
  for (double& i : ex.intensity) i = std::min(i, 120.0 / 255.0);
  datasets::ImageRenderOptions io;
  const datasets::ImageRenderer images(truth.sensor.camera);
  const Image8 img = images.RenderLaserLine(ex, io, 11);
  PeakDetectionOptions po;
  po.estimator = PeakEstimator::kBlaisRioux;
  const PeakDetectionResult peaks =
      DetectPeaks(ImageView8{img.pixels.data(), img.width, img.height, 0}, po);
  EXPECT_EQ(peaks.profile.ValidCount(), ex.ValidCount()) << peaks.Summary();

  const Triangulator tri(truth.sensor.camera, truth.sensor.laser.Coefficients());
  std::vector<Eigen::Vector3d> points(1024);
  tri.Triangulate(peaks.profile.row_px, 0, points);
  const Eigen::Vector3d m = cell_from_sensor.linear().transpose() * Eigen::Vector3d::UnitZ();
  // Row scatter bound: 3x the Cramer-Rao bound of a Gaussian stripe (peak_detection_test
  // measures Blais-Rioux at ~1.2x), for this column's amplitude and width; 6 sigma.
  const double sigma_n = std::sqrt(io.noise_sigma * io.noise_sigma + 1.0 / 12);
  int checked = 0;
  for (int c = 0; c < 1024; ++c) {
    if (std::isnan(points[c].x()) || std::isnan(ex.row_px[c])) continue;
    const double amplitude = 255.0 * ex.intensity[c];
    const double s = ex.width_px[c] / 2.3548200450309493;
    const double sigma_row =
        3.0 * sigma_n / amplitude * std::sqrt(2 * s / std::sqrt(std::numbers::pi));
    const double row = ex.row_px[c];
    const Eigen::Vector3d dp_dv =
        (tri.TriangulateExact(c, row + 1e-3) - tri.TriangulateExact(c, row - 1e-3)) / 2e-3;
    const double dist = (cell_from_sensor * points[c]).z() - height;
    ASSERT_LT(std::abs(dist), 6 * sigma_row * std::abs(m.dot(dp_dv))) << "column " << c;
    ++checked;
  }
  EXPECT_GT(checked, 900);
}

}  // namespace
}  // namespace lasercell::triangulation
