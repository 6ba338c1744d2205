#pragma once
// The inputs of the white-plane laser calibration (calib::CalibrateLaserPlaneFromHeights) from
// recorded profile files: the sweeps plane_<i>.lcp of the plate at heights_mm[i]
// (records/planes.yaml, calib/laser_plane_heights_record.hpp), each turned into the (column,
// subpixel row) peaks of all its profiles. Here and not in calib: the profile format
// (triangulation/profile_io.hpp) is triangulation's, and calib does not depend on it.

#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "calib/laser_plane.hpp"
#include "core/provenance.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell::triangulation {

/// The plane_<i>.lcp files of `dir` (or of dir/profiles when `dir` holds none), ordered by i.
/// FileError when neither folder holds any.
std::vector<std::string> FindPlaneProfileFiles(const std::string& dir);

/// One capture: every valid peak of `set` as (first_column + j, row_px[j]), named `name`, at
/// `height_mm` along the plate normal.
calib::HeightCapture HeightCaptureFromProfiles(const ProfileSet& set, const std::string& name,
                                               double height_mm);

/// Reads files[i] as the capture at heights_mm[i] (sizes must match: OptionError otherwise).
/// FileError when a file's sensor size differs from the camera model's. Each file's bytes are
/// added to `digest` when it is not null (provenance of the calibration).
std::vector<calib::HeightCapture> LoadHeightCaptures(const std::vector<std::string>& files,
                                                     const std::vector<double>& heights_mm,
                                                     const calib::CameraModel& camera,
                                                     InputDigest* digest = nullptr);

/// Method (a) of `calibrate laser` from files: the plane_<i>.lcp files of `dir`
/// (FindPlaneProfileFiles) at heights_mm[i] (LoadHeightCaptures, their bytes added to `digest`
/// when not null), then calib::CalibrateLaserPlaneFromHeights. Throws what those throw.
calib::LaserPlaneResult CalibrateLaserPlaneFromPlaneFiles(const calib::CameraModel& camera,
                                                          const std::string& dir,
                                                          const std::vector<double>& heights_mm,
                                                          const calib::HeightPlaneOptions& options,
                                                          InputDigest* digest = nullptr);

/// Method (b) of `calibrate laser` from image files: each read (its bytes added to `digest` when
/// not null) and decoded (calib::DecodeStripeImage), then calib::CalibrateLaserPlaneFromStripes.
/// FileError naming an unreadable file; otherwise what those throw.
calib::LaserPlaneResult CalibrateLaserPlaneFromStripeFiles(const calib::CameraModel& camera,
                                                           const std::vector<std::string>& paths,
                                                           const calib::BoardSpec& board,
                                                           const calib::StripeOptions& options,
                                                           InputDigest* digest = nullptr);

}  // namespace lasercell::triangulation
