#pragma once
// What `lasercell calibrate laser` writes about a laser-plane fit (calib/laser_plane.hpp): the
// versioned JSON summary ("lasercell.laser_plane", version 1), the HTML report (core/html_report:
// summary, per height/image table and RMS bars, residual histogram, residual along the line,
// stripe coverage of the image) and the cell's `laser` plane entry. Fill only; tools write.

#include <nlohmann/json.hpp>
#include <string>

#include "calib/camera_model.hpp"
#include "calib/laser_plane.hpp"
#include "core/frame_graph.hpp"
#include "core/html_report.hpp"

namespace lasercell::calib {

/// The JSON summary: plane {normal, offset_mm, point_mm} in the sensor frame, covariance over
/// [n; d], sigmas, RMS, conditioning, leave-one-out, per-height ("heights") or per-image
/// ("images") items, warnings. `camera` names the camera model file. Non-finite numbers: null.
nlohmann::json LaserPlaneJson(const LaserPlaneResult& result, const std::string& camera);

/// The HTML report; `camera` sizes the stripe-coverage plot.
report::HtmlReport LaserPlaneReport(const LaserPlaneResult& result, const CameraModel& camera);

/// The cell's laser-plane entry (frame `sensor`) for `result`, with `provenance` whose
/// residual_summary is filled here (method, RMS, points, 1-sigma).
LaserPlaneEntry LaserPlaneCellEntry(const LaserPlaneResult& result, EdgeProvenance provenance);

}  // namespace lasercell::calib
